//! `view_feature` and `view_info` (written by the render helper).

use super::MatchContext;
use crate::error::{Error, Result};
use crate::matching::MatchInfo;
use std::path::Path;

pub fn view_feature(_ctx: &MatchContext, _info: &MatchInfo, _out: &Path) -> Result<()> {
    Err(Error::InvalidArgument("view_feature is not available yet".into()))
}

pub fn view_info(_ctx: &MatchContext, _info: &MatchInfo, _out: &Path) -> Result<()> {
    Err(Error::InvalidArgument("view_info is not available yet".into()))
}
