//! `detect_api_mode`: the radio asked its `AP`, over a real TCP socket to the virtual
//! network's coordinator in either mode, and to a peer that says nothing.

#[cfg(unix)]
use std::time::Duration;

use mcp_host::sim::{Simulator, fleet_addresses};
use mcp_host::xbee_api::ApiMode;
use mcp_host::{Link, LinkOptions, detect_api_mode};
// For the test that also asks a pseudo-terminal (Unix only).
#[cfg(unix)]
use mcp_host::{DetectError, SendError};

/// A simulator whose coordinator is in `mode`, on a TCP port, and the link to it.
async fn radio_in(mode: ApiMode) -> (Simulator, Link) {
    let listen = "tcp-listen:127.0.0.1:0".parse().unwrap();
    let sim = Simulator::start(
        &listen,
        mode,
        &fleet_addresses(1),
        Simulator::network_config(),
    )
    .await
    .unwrap();
    let addr = sim.coordinator().local_addr.unwrap();
    let link = format!("tcp:{addr}").parse().unwrap();
    (sim, link)
}

#[tokio::test]
async fn the_radio_says_its_mode_whichever_it_is() {
    for mode in [ApiMode::Unescaped, ApiMode::Escaped] {
        let (_sim, link) = radio_in(mode).await;
        // Whatever mode the options give: the question reads the same in both.
        for given in [ApiMode::Unescaped, ApiMode::Escaped] {
            let options = LinkOptions {
                api_mode: given,
                ..LinkOptions::default()
            };
            assert_eq!(detect_api_mode(&link, options).await.unwrap(), mode);
        }
    }
}

#[cfg(unix)]
#[tokio::test]
async fn a_radio_that_does_not_answer_and_a_link_with_no_radio_say_so() {
    // A peer that reads and says nothing, as a radio in transparent mode.
    let silent = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let link: Link = format!("tcp:{}", silent.local_addr().unwrap())
        .parse()
        .unwrap();
    let peer = tokio::spawn(async move {
        let (mut socket, _) = silent.accept().await.unwrap();
        let _ = tokio::io::copy(&mut socket, &mut tokio::io::sink()).await;
    });
    let options = LinkOptions {
        send_timeout: Duration::from_millis(200),
        ..LinkOptions::default()
    };
    let error = detect_api_mode(&link, options).await.unwrap_err();
    assert!(
        matches!(error, DetectError::NoAnswer(SendError::Timeout { .. })),
        "{error:?}"
    );
    assert!(
        error
            .to_string()
            .starts_with("the radio did not answer AT AP: no answer to frame id 1 within "),
        "{error}"
    );
    // The link was closed: the peer saw its end.
    tokio::time::timeout(Duration::from_secs(20), peer)
        .await
        .expect("the link closed")
        .unwrap();

    for link in ["pty", "tcp-listen:127.0.0.1:0"] {
        let link: Link = link.parse().unwrap();
        let error = detect_api_mode(&link, LinkOptions::default())
            .await
            .unwrap_err();
        assert!(matches!(error, DetectError::NoRadio(_)), "{error:?}");
    }
}
