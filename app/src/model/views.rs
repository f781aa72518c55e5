//! The page's state, one context per view: the explorer's [`Lab`] (the pair,
//! the strategy, the analysis) that the matching views share, and the state
//! each other view owns. The URL reads and writes all of them.

use crate::model::exercise::ExerciseState;
use crate::model::lab::Lab;
use crate::model::mark::MarkState;
use crate::model::see_inside::Inside;
use leptos::prelude::*;

#[derive(Clone, Copy)]
pub struct Views {
    pub lab: Lab,
    pub exercises: ExerciseState,
    pub mark: MarkState,
    pub inside: Inside,
}

impl Views {
    pub fn new() -> Self {
        Self::with_lab(Lab::new())
    }

    /// A given explorer state with fresh state for every other view.
    pub fn with_lab(lab: Lab) -> Self {
        Views { lab, exercises: ExerciseState::new(), mark: MarkState::new(), inside: Inside::new() }
    }

    /// Each view's state as its own context (`expect_context::<Inside>()`, …).
    pub fn provide(self) {
        provide_context(self.lab);
        provide_context(self.exercises);
        provide_context(self.mark);
        provide_context(self.inside);
    }
}

impl Default for Views {
    fn default() -> Self {
        Self::new()
    }
}
