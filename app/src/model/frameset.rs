//! Which frames a source has, and what the lab's frame arguments ask of it:
//! `get_info FRAME_ID` needs frames FRAME_ID−1 and FRAME_ID, `view_trajectory
//! FRAME_ID` needs every frame 0 … FRAME_ID. Plain functions, so the messages
//! the page shows are tested natively.

/// Frame ids for reading: runs of three or more as `a–b`, the rest one by one
/// (`0–99, 119, 120, 149, 150`), so a gap in the bundled demo is visible.
pub fn describe_ids(ids: &[u32]) -> String {
    let mut sorted = ids.to_vec();
    sorted.sort_unstable();
    sorted.dedup();
    let mut parts = Vec::new();
    let mut i = 0;
    while i < sorted.len() {
        let mut j = i;
        while j + 1 < sorted.len() && sorted[j + 1] == sorted[j] + 1 {
            j += 1;
        }
        if j - i >= 2 {
            parts.push(format!("{}–{}", sorted[i], sorted[j]));
        } else {
            parts.extend(sorted[i..=j].iter().map(u32::to_string));
        }
        i = j + 1;
    }
    parts.join(", ")
}

/// Whether `ids` holds the pair `get_info FRAME_ID` matches.
pub fn has_pair(ids: &[u32], frame_id: u32) -> bool {
    frame_id >= 1 && ids.contains(&(frame_id - 1)) && ids.contains(&frame_id)
}

/// The first FRAME_ID whose pair is there: what a source opens on.
pub fn first_pair(ids: &[u32]) -> Option<u32> {
    let mut sorted = ids.to_vec();
    sorted.sort_unstable();
    sorted.into_iter().find(|&f| has_pair(ids, f))
}

/// Why `get_info FRAME_ID` cannot run on `ids` (`where_`: "the demo", "the
/// folder"), naming the missing frames and the ones there are; `None` if it can.
pub fn missing_pair_message(where_: &str, ids: &[u32], frame_id: u32) -> Option<String> {
    if frame_id < 1 {
        return Some("FRAME_ID must be at least 1: frames FRAME_ID−1 and FRAME_ID are matched".into());
    }
    let missing: Vec<u32> = [frame_id - 1, frame_id].into_iter().filter(|f| !ids.contains(f)).collect();
    let which = match missing.as_slice() {
        [] => return None,
        [f] => format!("frame {f} is"),
        _ => format!("frames {} and {frame_id} are", frame_id - 1),
    };
    Some(format!(
        "FRAME_ID {frame_id} needs frames {} and {frame_id}: {which} not in {where_}, which has frames {}",
        frame_id - 1,
        describe_ids(ids)
    ))
}

/// How many frames follow each other from frame 0 (0, 1, 2, … with no gap):
/// what the odometry can run over.
pub fn run_from_zero(ids: &[u32]) -> u32 {
    (0..).take_while(|i| ids.contains(i)).count() as u32
}

/// `frames 0 to 99 (100 frames)`: what `view_trajectory FRAME_ID` runs over.
pub fn vo_range_text(frame_id: u32) -> String {
    // In u64: FRAME_ID 4294967295 (a link or the box can say it) overflowed
    // u32 (found by fuzzing, tests/fuzz/regressions/app_state).
    format!("frames 0 to {frame_id} ({} frames)", frame_id as u64 + 1)
}

/// What the odometry's FRAME_ID box reads as, beside it: the frames it asks
/// for (if it is a number) and the run from 0 the source has.
pub fn vo_range_label(text: &str, run: u32) -> String {
    let have = match run {
        0 => "no frame 0 to start from".to_string(),
        _ => format!("available: frames 0 to {}", run - 1),
    };
    match text.trim().parse::<u32>() {
        Ok(last) => format!("{} · {have}", vo_range_text(last)),
        Err(_) => have,
    }
}

/// The odometry's FRAME_ID box → the number of frames to run (FRAME_ID + 1,
/// as the lab's `view_trajectory` counts), given `run` frames from 0 in a row.
pub fn vo_frame_count(text: &str, run: u32) -> Result<u32, String> {
    let t = text.trim();
    let last = t.parse::<u32>().map_err(|_| format!("FRAME_ID {t:?} is not a whole number ≥ 1"))?;
    if last < 1 {
        return Err("FRAME_ID must be at least 1: the odometry needs two frames (0 and 1)".into());
    }
    if last >= run {
        let have = if run == 0 { "no frame 0".to_string() } else { vo_range_text(run - 1) };
        return Err(format!(
            "FRAME_ID {last} needs {}, but the frames in a row from 0 are {have}",
            vo_range_text(last)
        ));
    }
    Ok(last + 1)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn demo() -> Vec<u32> {
        (0..100).chain([119, 120, 149, 150]).collect()
    }

    #[test]
    fn ids_read_as_runs_and_singles() {
        assert_eq!(describe_ids(&demo()), "0–99, 119, 120, 149, 150");
        assert_eq!(describe_ids(&[5, 3, 4, 9]), "3–5, 9");
        assert_eq!(describe_ids(&[1]), "1");
        assert_eq!(describe_ids(&[]), "");
    }

    #[test]
    fn pairs_of_the_demo() {
        let ids = demo();
        assert_eq!(first_pair(&ids), Some(1));
        assert!(has_pair(&ids, 99) && has_pair(&ids, 120) && has_pair(&ids, 150));
        assert!(!has_pair(&ids, 0) && !has_pair(&ids, 100) && !has_pair(&ids, 119));
        assert_eq!(first_pair(&[4, 7, 8]), Some(8));
        assert_eq!(first_pair(&[4, 7]), None);
    }

    #[test]
    fn a_missing_pair_names_the_missing_and_the_available_frames() {
        let ids = demo();
        assert_eq!(missing_pair_message("the demo", &ids, 150), None);
        assert_eq!(
            missing_pair_message("the demo", &ids, 130).unwrap(),
            "FRAME_ID 130 needs frames 129 and 130: frames 129 and 130 are not in the demo, \
             which has frames 0–99, 119, 120, 149, 150"
        );
        assert_eq!(
            missing_pair_message("the demo", &ids, 119).unwrap(),
            "FRAME_ID 119 needs frames 118 and 119: frame 118 is not in the demo, which has frames 0–99, 119, 120, 149, 150"
        );
        assert!(missing_pair_message("the folder", &ids, 100).unwrap().contains("frame 100 is not in the folder"));
        assert!(missing_pair_message("the demo", &ids, 0).unwrap().contains("at least 1"));
    }

    #[test]
    fn the_odometry_counts_as_view_trajectory() {
        let run = run_from_zero(&demo());
        assert_eq!(run, 100, "119, 120, 149, 150 are not contiguous with 0–99");
        assert_eq!(run_from_zero(&[1, 2, 3]), 0);
        assert_eq!(vo_range_text(99), "frames 0 to 99 (100 frames)");
        assert_eq!(vo_frame_count("99", run), Ok(100));
        assert_eq!(vo_frame_count(" 1 ", run), Ok(2));
        assert!(vo_frame_count("0", run).unwrap_err().contains("at least 1"));
        assert_eq!(
            vo_frame_count("120", run).unwrap_err(),
            "FRAME_ID 120 needs frames 0 to 120 (121 frames), but the frames in a row from 0 are frames 0 to 99 (100 frames)"
        );
        assert!(vo_frame_count("ten", run).unwrap_err().contains("not a whole number"));
        assert_eq!(vo_range_label("99", run), "frames 0 to 99 (100 frames) · available: frames 0 to 99");
        assert_eq!(vo_range_label("", run), "available: frames 0 to 99");
        assert_eq!(vo_range_label("3", 0), "frames 0 to 3 (4 frames) · no frame 0 to start from");
    }
}
