//! "See inside": the state of the two views that open SIFT and the matcher
//! up, and, as in `page/see_inside/`, the plain functions each view's
//! components delegate to (tested natively): SIFT's [`anatomy`], the
//! [`whole_frame`] matching and its [`tradeoff`] chart.

pub mod anatomy;
pub mod tradeoff;
pub mod whole_frame;

use leptos::prelude::*;

/// Which "see inside" view is open.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum InsideView {
    Anatomy,
    Matches,
}

impl InsideView {
    /// The URL's `see=` value.
    pub fn name(self) -> &'static str {
        match self {
            InsideView::Anatomy => "anatomy",
            InsideView::Matches => "matches",
        }
    }

    pub fn parse(s: &str) -> Option<InsideView> {
        [InsideView::Anatomy, InsideView::Matches].into_iter().find(|v| v.name() == s)
    }
}

/// The views' state (part of the URL: `see`, `px`, `kp`).
#[derive(Clone, Copy)]
pub struct Inside {
    pub view: RwSignal<Option<InsideView>>,
    /// The Sampson threshold in pixels, as typed.
    pub px: RwSignal<String>,
    /// The anatomy's selected keypoint (an index into the frame's keypoints).
    pub kp: RwSignal<Option<usize>>,
}

impl Inside {
    pub fn new() -> Self {
        Inside { view: RwSignal::new(None), px: RwSignal::new("2".into()), kp: RwSignal::new(None) }
    }
}

impl Default for Inside {
    fn default() -> Self {
        Self::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn views_parse() {
        assert_eq!(InsideView::parse("matches"), Some(InsideView::Matches));
        assert_eq!(InsideView::parse(InsideView::Anatomy.name()), Some(InsideView::Anatomy));
        assert_eq!(InsideView::parse("x"), None);
    }
}
