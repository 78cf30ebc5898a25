//! `mcp-gs demo` (not implemented yet).

use clap::Args;

use crate::Failure;

/// Arguments of `demo`.
#[derive(Debug, Args)]
pub(crate) struct DemoArgs {}

/// Runs `demo`.
pub(crate) async fn run(_args: DemoArgs) -> Result<(), Failure> {
    Err(Failure::new(
        Failure::OTHER,
        "`demo` is not implemented yet",
    ))
}
