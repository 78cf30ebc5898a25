//! Link strings: every link displays to a string that parses back to it.

use mcp_host::Link;
use mcp_host::link::FlowControl;
use proptest::prelude::*;

fn link() -> impl Strategy<Value = Link> {
    let host = prop_oneof![
        "[a-z][a-z0-9.-]{0,20}",
        any::<std::net::Ipv4Addr>().prop_map(|a| a.to_string()),
        any::<std::net::Ipv6Addr>().prop_map(|a| a.to_string()),
    ];
    // A device's name ends in no word of letters after a colon: such a word is an
    // option (`:rtscts`), or a mistyped one, refused.
    let path = "[^\\x00]{1,40}".prop_filter("no word after a colon", |path: &String| {
        path.rsplit_once(':').is_none_or(|(_, word)| {
            !word
                .trim()
                .bytes()
                .all(|b| b.is_ascii_alphabetic() || b"/-_".contains(&b))
        })
    });
    prop_oneof![
        (path, 1u32.., any::<bool>()).prop_map(|(path, baud, rts_cts)| {
            let flow_control = if rts_cts {
                FlowControl::RtsCts
            } else {
                FlowControl::None
            };
            Link::serial_with(path, baud, flow_control)
        }),
        // Port 0 is refused for a peer (`PortZero`); it means any port to listen on.
        (host.clone(), 1u16..).prop_map(|(host, port)| Link::tcp(host, port)),
        (host, any::<u16>()).prop_map(|(addr, port)| Link::tcp_listen(addr, port)),
        Just(Link::Pty),
        "\\PC{1,20}".prop_map(Link::io),
    ]
}

proptest! {
    #[test]
    fn display_then_parse_is_identity(link in link()) {
        let text = link.to_string();
        prop_assert_eq!(text.parse::<Link>(), Ok(link));
    }

    #[test]
    fn host_and_port_text_rich_in_brackets_and_slashes_reads_back(
        text in "(tcp|tcp-listen):(\\[[\\[\\]/:a1 \u{0}]{0,3}\\]|[\\[\\]/a1]{1,3}):[0-9]{1,3}"
    ) {
        if let Ok(link) = text.parse::<Link>() {
            prop_assert_eq!(link.to_string().parse::<Link>(), Ok(link));
        }
    }

    #[test]
    fn parsing_arbitrary_text_never_panics(text in "\\PC{0,60}") {
        if let Ok(link) = text.parse::<Link>() {
            // Whatever parses displays to something that parses to the same link.
            prop_assert_eq!(link.to_string().parse::<Link>(), Ok(link));
        }
    }
}
