//! The output order (docs/fidelity.md §SIFT-10): `removeDuplicatedSorted`, then
//! `KeyPointsFilter::retainBest` with libstdc++'s `nth_element`
//! (introselect) and `partition`, then the firstOctave = −1 rescale.
//!
//! OpenCV's feature ids are whatever positions these algorithms leave, so
//! they are reproduced move for move, not just "sorted by response".

use super::keypoint::KeyPoint;
#[cfg(test)]
use std::cmp::Ordering;

/// The strict total order of `KeypointGreater` used before deduplication
/// (sorted by its integer form, [`order_key`]).
#[cfg(test)]
fn keypoint_order(a: &KeyPoint, b: &KeyPoint) -> Ordering {
    let f = |x: f32, y: f32| x.partial_cmp(&y).unwrap_or(Ordering::Equal);
    f(a.x, b.x)
        .then(f(a.y, b.y))
        .then(f(b.size, a.size))
        .then(f(a.angle, b.angle))
        .then(f(b.response, a.response))
        .then(b.octave.cmp(&a.octave))
}

/// [`keypoint_order`] as one integer key per keypoint: each f32 mapped to
/// an unsigned integer of the same order (−0 taken as +0, as `partial_cmp`
/// has them equal), negated where the order is descending.
fn order_key(k: &KeyPoint) -> (u128, u64) {
    let up = |v: f32| {
        let b = (v + 0.0).to_bits();
        if b >> 31 == 1 {
            !b
        } else {
            b | 1 << 31
        }
    };
    let down = |v: f32| !up(v);
    let octave_down = !((k.octave as u32) ^ 1 << 31);
    (
        (up(k.x) as u128) << 96 | (up(k.y) as u128) << 64 | (down(k.size) as u128) << 32 | up(k.angle) as u128,
        (down(k.response) as u64) << 32 | octave_down as u64,
    )
}

/// Sorts and drops keypoints whose (x, y, size, angle) equal the last kept one.
/// Keypoints the order calls equal agree in every field (up to the sign of
/// a zero), so any sort leaves the same sequence, as OpenCV's `std::sort`
/// does. Sorting by a key computed once per keypoint took a third of the
/// time of calling the comparison chain at every step.
pub fn remove_duplicated_sorted(kps: &mut Vec<KeyPoint>) {
    kps.sort_by_cached_key(order_key);
    kps.dedup_by(|b, a| a.x == b.x && a.y == b.y && a.size == b.size && a.angle == b.angle);
}

#[inline(always)]
fn comp(a: &KeyPoint, b: &KeyPoint) -> bool {
    a.response > b.response
}

/// `KeyPointsFilter::retainBest`: nth_element on response, then keep every
/// keypoint of the tail that ties the cut's response.
pub fn retain_best(kps: &mut Vec<KeyPoint>, n: usize) {
    if n == 0 || kps.len() <= n {
        return;
    }
    nth_element(kps, n - 1);
    let amb = kps[n - 1].response;
    let end = partition(&mut kps[n..], |k| k.response >= amb);
    kps.truncate(n + end);
}

/// libstdc++ `std::__introselect` with `__lg(n) * 2` depth.
fn nth_element(a: &mut [KeyPoint], nth: usize) {
    let (mut first, mut last) = (0usize, a.len());
    if first == last || nth >= last {
        return;
    }
    let mut depth = 2 * (usize::BITS - 1 - last.leading_zeros()) as usize;
    while last - first > 3 {
        if depth == 0 {
            heap_select(a, first, nth + 1, last);
            a.swap(first, nth);
            return;
        }
        depth -= 1;
        let cut = partition_pivot(a, first, last);
        if cut <= nth {
            first = cut;
        } else {
            last = cut;
        }
    }
    insertion_sort(a, first, last);
}

fn partition_pivot(a: &mut [KeyPoint], f: usize, l: usize) -> usize {
    let mid = f + (l - f) / 2;
    move_median_to_first(a, f, f + 1, mid, l - 1);
    unguarded_partition(a, f + 1, l, f)
}

fn move_median_to_first(arr: &mut [KeyPoint], result: usize, a: usize, b: usize, c: usize) {
    if comp(&arr[a], &arr[b]) {
        if comp(&arr[b], &arr[c]) {
            arr.swap(result, b);
        } else if comp(&arr[a], &arr[c]) {
            arr.swap(result, c);
        } else {
            arr.swap(result, a);
        }
    } else if comp(&arr[a], &arr[c]) {
        arr.swap(result, a);
    } else if comp(&arr[b], &arr[c]) {
        arr.swap(result, c);
    } else {
        arr.swap(result, b);
    }
}

fn unguarded_partition(a: &mut [KeyPoint], mut f: usize, mut l: usize, p: usize) -> usize {
    loop {
        while comp(&a[f], &a[p]) {
            f += 1;
        }
        l -= 1;
        while comp(&a[p], &a[l]) {
            l -= 1;
        }
        if f >= l {
            return f;
        }
        a.swap(f, l);
        f += 1;
    }
}

fn insertion_sort(a: &mut [KeyPoint], f: usize, l: usize) {
    if f == l {
        return;
    }
    for i in f + 1..l {
        let v = a[i];
        if comp(&v, &a[f]) {
            a.copy_within(f..i, f + 1);
            a[f] = v;
        } else {
            let mut j = i;
            while comp(&v, &a[j - 1]) {
                a[j] = a[j - 1];
                j -= 1;
            }
            a[j] = v;
        }
    }
}

fn heap_select(a: &mut [KeyPoint], f: usize, m: usize, l: usize) {
    make_heap(a, f, m);
    for i in m..l {
        if comp(&a[i], &a[f]) {
            let v = a[i];
            a[i] = a[f];
            adjust_heap(a, f, 0, m - f, v);
        }
    }
}

fn make_heap(a: &mut [KeyPoint], f: usize, m: usize) {
    let len = m - f;
    if len < 2 {
        return;
    }
    let mut parent = (len - 2) / 2;
    loop {
        let v = a[f + parent];
        adjust_heap(a, f, parent, len, v);
        if parent == 0 {
            return;
        }
        parent -= 1;
    }
}

fn adjust_heap(a: &mut [KeyPoint], f: usize, mut hole: usize, len: usize, v: KeyPoint) {
    let top = hole;
    let mut child = hole;
    while child < (len - 1) / 2 {
        child = 2 * (child + 1);
        if comp(&a[f + child], &a[f + child - 1]) {
            child -= 1;
        }
        a[f + hole] = a[f + child];
        hole = child;
    }
    if len.is_multiple_of(2) && child == (len - 2) / 2 {
        child = 2 * (child + 1);
        a[f + hole] = a[f + child - 1];
        hole = child - 1;
    }
    // __push_heap
    let mut parent = hole.wrapping_sub(1) / 2;
    while hole > top && comp(&a[f + parent], &v) {
        a[f + hole] = a[f + parent];
        hole = parent;
        parent = hole.wrapping_sub(1) / 2;
    }
    a[f + hole] = v;
}

/// libstdc++'s bidirectional `std::partition`; returns the split point.
fn partition(a: &mut [KeyPoint], pred: impl Fn(&KeyPoint) -> bool) -> usize {
    let (mut f, mut l) = (0usize, a.len());
    loop {
        loop {
            if f == l {
                return f;
            }
            if pred(&a[f]) {
                f += 1;
            } else {
                break;
            }
        }
        loop {
            l -= 1;
            if f == l {
                return f;
            }
            if pred(&a[l]) {
                break;
            }
        }
        a.swap(f, l);
        f += 1;
    }
}

/// Undoes the doubled base: octave byte o → o − 1, coordinates and size ×0.5.
pub fn rescale_first_octave(kps: &mut [KeyPoint]) {
    for kp in kps {
        kp.octave = (kp.octave & !255) | ((kp.octave - 1) & 255);
        kp.x *= 0.5;
        kp.y *= 0.5;
        kp.size *= 0.5;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn kp(resp: f32, x: f32) -> KeyPoint {
        KeyPoint { x, y: 0.0, size: 1.0, angle: 0.0, response: resp, octave: 0 }
    }

    /// The integer key orders every pair as the comparison chain does, on
    /// keypoints drawn from few values per field so that every field gets to
    /// decide some pairs (±0, negatives and subnormals included).
    #[test]
    fn order_key_is_keypoint_order() {
        let vals = [-3.5f32, -0.0, 0.0, 1e-40, 0.5, 0.5000001, 7.0, 1241.25];
        let mut s = 0x1357_9bdfu32;
        let mut pick = || {
            s ^= s << 13;
            s ^= s >> 17;
            s ^= s << 5;
            s
        };
        let kps: Vec<KeyPoint> = (0..300)
            .map(|_| KeyPoint {
                x: vals[pick() as usize % 3 + 3],
                y: vals[pick() as usize % 3 + 2],
                size: vals[pick() as usize % 8],
                angle: vals[pick() as usize % 4],
                response: vals[pick() as usize % 8],
                octave: [-1, 0, 0x0101, 0x7f0201, -255][pick() as usize % 5],
            })
            .collect();
        for a in &kps {
            for b in &kps {
                assert_eq!(order_key(a).cmp(&order_key(b)), keypoint_order(a, b), "{a:?} {b:?}");
            }
        }
    }

    #[test]
    fn retain_best_keeps_ties_and_the_best() {
        let mut v: Vec<KeyPoint> =
            [5.0, 1.0, 3.0, 3.0, 9.0, 3.0, 2.0].iter().enumerate().map(|(i, &r)| kp(r, i as f32)).collect();
        retain_best(&mut v, 3);
        let mut resp: Vec<f32> = v.iter().map(|k| k.response).collect();
        resp.sort_by(|a, b| b.partial_cmp(a).unwrap());
        // 9, 5 and the three tied 3s: the tie at the cut is kept.
        assert_eq!(resp, vec![9.0, 5.0, 3.0, 3.0, 3.0]);
    }

    #[test]
    fn nth_element_partitions_like_libstdcxx() {
        // A large list forces the introselect loop; whatever the order, the
        // first n must hold the n largest responses.
        let mut state = 12345u32;
        let mut v: Vec<KeyPoint> = (0..5000)
            .map(|i| {
                state = state.wrapping_mul(1664525).wrapping_add(1013904223);
                kp((state >> 8) as f32, i as f32)
            })
            .collect();
        let mut sorted: Vec<f32> = v.iter().map(|k| k.response).collect();
        sorted.sort_by(|a, b| b.partial_cmp(a).unwrap());
        nth_element(&mut v, 1499);
        assert_eq!(v[1499].response, sorted[1499]);
        assert!(v[..1499].iter().all(|k| k.response >= sorted[1499]));
        assert!(v[1500..].iter().all(|k| k.response <= sorted[1499]));
    }

    #[test]
    fn dedup_drops_exact_duplicates_keeping_the_best_response() {
        let mut v = vec![kp(1.0, 2.0), kp(3.0, 2.0), kp(2.0, 1.0)];
        remove_duplicated_sorted(&mut v);
        assert_eq!(v.len(), 2);
        assert_eq!((v[0].x, v[1].x, v[1].response), (1.0, 2.0, 3.0));
    }

    #[test]
    fn rescale_octave_byte() {
        let mut v = vec![KeyPoint { x: 4.0, y: 2.0, size: 3.0, angle: 0.0, response: 1.0, octave: 0xC00202 }];
        rescale_first_octave(&mut v);
        assert_eq!(v[0].octave, 0xC00201);
        let mut w = vec![KeyPoint { octave: 0x000100, ..v[0] }];
        rescale_first_octave(&mut w);
        assert_eq!(w[0].octave, 0x0001FF);
        assert_eq!((v[0].x, v[0].y, v[0].size), (2.0, 1.0, 1.5));
    }
}
