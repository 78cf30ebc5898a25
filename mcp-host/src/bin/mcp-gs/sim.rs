//! `mcp-gs sim` (not implemented yet).

use clap::Args;

use crate::Failure;

/// Arguments of `sim`.
#[derive(Debug, Args)]
pub(crate) struct SimArgs {}

/// Runs `sim`.
pub(crate) async fn run(_args: SimArgs) -> Result<(), Failure> {
    Err(Failure::new(Failure::OTHER, "`sim` is not implemented yet"))
}
