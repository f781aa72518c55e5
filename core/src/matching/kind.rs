//! The strategies' names: dt, nn or nndr without a threshold, as a menu, a
//! link or an exercise picks one before its threshold is known.

/// A strategy without its threshold: what a menu, a link or an exercise picks
/// before the threshold is known. Its names are the lab's `-a` values.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum StrategyKind {
    Dt,
    Nn,
    Nndr,
}

impl StrategyKind {
    /// The three, in the lab's order.
    pub const ALL: [StrategyKind; 3] = [StrategyKind::Dt, StrategyKind::Nn, StrategyKind::Nndr];

    /// The lab's name (`-a`).
    pub fn name(self) -> &'static str {
        match self {
            StrategyKind::Dt => "dt",
            StrategyKind::Nn => "nn",
            StrategyKind::Nndr => "nndr",
        }
    }

    /// The kind named `name` (exactly `dt`, `nn` or `nndr`), if any.
    pub fn parse(name: &str) -> Option<StrategyKind> {
        StrategyKind::ALL.into_iter().find(|k| k.name() == name)
    }
}
