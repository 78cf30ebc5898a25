//! Property: whatever frames a device writes, the network keeps routing.

use std::time::Duration;

use futures::{SinkExt, StreamExt};
use mcp_host::codec::{CodecItem, XBeeCodec};
use mcp_host::radio::{Network, NetworkConfig, NodeOptions};
use proptest::prelude::*;
use tokio_util::codec::Framed;
use xbee_api::{Address16, Address64, ApiMode, Frame, RawFrame, TransmitRequestRepr};

/// Failure guard only.
const GUARD: Duration = Duration::from_secs(20);
const MAV: Address64 = Address64(0x0013_A200_40B5_99B9);

fn frame_data() -> impl Strategy<Value = Vec<u8>> {
    // Mostly the frame types the radio acts on, with arbitrary (often short) bodies.
    (
        prop_oneof![
            Just(0x08u8),
            Just(0x10),
            Just(0x11),
            Just(0x17),
            Just(0x90),
            any::<u8>()
        ],
        prop::collection::vec(any::<u8>(), 0..120),
    )
        .prop_map(|(t, mut body)| {
            body.insert(0, t);
            body
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn arbitrary_frames_never_stop_the_network(
        frames in prop::collection::vec(frame_data(), 1..12),
        mode in prop_oneof![Just(ApiMode::Unescaped), Just(ApiMode::Escaped)],
    ) {
        let rt = tokio::runtime::Builder::new_current_thread().enable_all().build().unwrap();
        rt.block_on(async {
            let network = Network::new(NetworkConfig::default());
            let (_, ground) = network
                .add_in_process(Address64::COORDINATOR, NodeOptions::default())
                .unwrap();
            let (_, mav) = network.add_in_process(MAV, NodeOptions::with_mode(mode)).unwrap();
            let mut ground = Framed::new(ground, XBeeCodec::new(ApiMode::Unescaped));
            let mut mav = Framed::new(mav, XBeeCodec::new(mode));
            for data in &frames {
                mav.send(&RawFrame::new(data).unwrap()).await.unwrap();
            }
            let marker = TransmitRequestRepr {
                frame_id: 0,
                dst64: Address64::COORDINATOR,
                dst16: Address16::UNKNOWN,
                radius: 0,
                options: 0,
                data: b"marker",
            };
            mav.send(&marker).await.unwrap();
            tokio::time::timeout(GUARD, async {
                loop {
                    match ground.next().await {
                        Some(Ok(CodecItem::Frame(f))) => {
                            if let Ok(Frame::ReceivePacket(rx)) = f.parse() {
                                if rx.src64 == MAV && rx.data == b"marker" {
                                    return;
                                }
                            }
                        }
                        Some(Ok(CodecItem::Error(e))) => panic!("decode error {e}"),
                        other => panic!("the coordinator's link ended: {other:?}"),
                    }
                }
            })
            .await
            .expect("the marker in time");
            // The MAV's device still reads its radio: drain what it got.
            while let Ok(Some(item)) = tokio::time::timeout(Duration::ZERO, mav.next()).await {
                prop_assert!(matches!(item, Ok(CodecItem::Frame(_))));
            }
            Ok(())
        })?;
    }
}
