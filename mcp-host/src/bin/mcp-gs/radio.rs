//! `mcp-gs radio` (not implemented yet).

use clap::Args;

use crate::Failure;

/// Arguments of `radio`.
#[derive(Debug, Args)]
pub(crate) struct RadioArgs {}

/// Runs `radio`.
pub(crate) async fn run(_args: RadioArgs) -> Result<(), Failure> {
    Err(Failure::new(
        Failure::OTHER,
        "`radio` is not implemented yet",
    ))
}
