//! The re-run of a request that reached its wall-clock limit waiting for a
//! CPU (docs/marking.md, "The sandbox": the machine's slowness is not the
//! file's): a fresh harness, given the load and the pair the request needs,
//! runs it once more.

use super::{Harness, Runner, Setup};
use siftlab_core::error::Result;
use siftlab_mark::{Outcome, Pair};

impl Runner {
    /// A request that hit its wall-clock limit waiting for a CPU (`why`),
    /// run once more in a fresh harness given the same file and pair
    /// first, whose wall-clock limits leave out the time spent waiting for
    /// a CPU (up to 4 × each limit): the machine's slowness is not the
    /// file's time-out. If the harness cannot be rebuilt, the first outcome
    /// stands.
    pub(super) fn rerun(
        &self,
        setup: &[Setup],
        (id, line, limit, op): (u64, &str, f64, &'static str),
        pairs: &[Pair],
        job: u32,
        why: &str,
        first: Outcome,
    ) -> Result<(Option<Harness>, Outcome)> {
        eprintln!("siftlab: a {op} request {why}: the machine's slowness, not the file's; running it again once");
        let mut h = Harness::start(&self.python, &self.dir.0, self.tier, job, self.cgroups, self.enclosing.clone())?;
        h.patient = true;
        let mut stray = 0;
        for (sid, sline, slimit, sop, _) in setup {
            if !matches!(h.request(sline, *sid, *slimit, pairs, &mut stray, sop), Outcome::Reply(..)) {
                return Ok((None, first));
            }
        }
        let outcome = h.request(line, id, limit, pairs, &mut stray, op);
        if let Some(again) = h.slow.take() {
            eprintln!(
                "siftlab: the re-run {again} too (4 x its limit): the machine is overloaded; the time-out stands"
            );
        }
        h.stray = stray;
        Ok((Some(h), outcome))
    }
}
