//! Link argument strings, `mcp_host::Link`'s `FromStr` (`--link`, a hub's radio, the
//! `MCP_LINK` a user types or a script passes): any text.
//!
//! Checks: no panic, the error's message formats; a link parsed prints (`Display`) as a
//! string that parses back to the same link, and prints the same again.
#![no_main]

use libfuzzer_sys::fuzz_target;
use mcp_host::Link;

fuzz_target!(|text: &str| {
    match text.parse::<Link>() {
        Ok(link) => {
            let shown = link.to_string();
            let again: Link = shown
                .parse()
                .unwrap_or_else(|e| panic!("{text:?} parsed to {link:?}, shown {shown:?}: {e}"));
            assert_eq!(again, link, "{text:?} shown as {shown:?}");
            assert_eq!(again.to_string(), shown);
        }
        Err(error) => {
            let _ = error.to_string();
        }
    }
});
