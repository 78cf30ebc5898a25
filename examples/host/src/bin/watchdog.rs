//! A fleet watchdog: finds every MAV the ground station's radio reaches, turns on each
//! one's altitude telemetry and prints a line per MAV per second; a MAV silent for 2 s
//! is asked its landing state, and said to be lost if it does not answer. It keeps
//! going across the link dropping and coming back: on each reconnection it looks for
//! MAVs again (a new one is watched too) and turns the telemetry on again (a restarted
//! MAV, or radio, has forgotten it). A MAV heard without being discovered is watched
//! as well.
//!
//! `watchdog [LINK] [SECONDS] [DISCOVERY_WINDOW]` (default: run until Ctrl-C, the
//! radio's discovery time).
//!
//! Lines, one per MAV per second:
//!
//! ```text
//! 0013a20040b599b9 ok altitude 1.00 m, 20 packets/s, heard 0.0 s ago
//! 0013a20040b599bf silent for 2.0 s: asking its landing state
//! 0013a20040b599bf lost: status request failed: delivery to ... failed: ...
//! 0013a20040b599bf answered: landing flight
//! ```

use std::collections::HashSet;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use futures::StreamExt;
use mcp_host::mcp_core::{Command, Packet, StatusRequest, TelemetryId};
use mcp_host::xbee_api::{Address64, DeviceType};
use mcp_host::{CommandSender, Event, LinkEvent, LinkOptions, LinkState, RequestError};
use tokio::sync::mpsc;
use tokio::time::Instant;

/// How long a MAV may stay silent before it is asked whether it is there.
const SILENCE: Duration = Duration::from_secs(2);
/// How long it has to answer.
const PROBE_TIMEOUT: Duration = Duration::from_secs(2);

#[tokio::main]
async fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let link = mcp_host_examples::link(args.next())?;
    let seconds: u64 = args.next().map_or(Ok(0), |s| s.parse())?;
    let window: Option<Duration> = args
        .next()
        .map(|s| s.parse::<f64>().map(Duration::from_secs_f64))
        .transpose()?;

    let (stream, sender) = mcp_host::connect(&link, LinkOptions::default()).await?;
    let watched: Arc<Mutex<HashSet<Address64>>> = Arc::default();
    spawn_discovery(&sender, window, &watched);

    // Every event until Ctrl-C or the time is up (or the link has ended).
    let end = async {
        if seconds == 0 {
            let _ = tokio::signal::ctrl_c().await;
        } else {
            tokio::time::sleep(Duration::from_secs(seconds)).await;
        }
    };
    let mut events = std::pin::pin!(stream.take_until(end));
    while let Some(event) = events.next().await {
        match event {
            // A MAV discovery missed (it came in range later): watched from now on.
            Event::Packet(rx) => {
                let mav = rx.origin.src64;
                if watched.lock().unwrap().insert(mav) {
                    println!("{mav} heard without being discovered: watching it");
                    spawn_watcher(&sender, mav);
                }
            }
            Event::Link(LinkEvent::Reconnected { .. }) => {
                println!("{event}");
                // Whoever is in range now: the watchers turn telemetry on again
                // themselves.
                spawn_discovery(&sender, window, &watched);
            }
            Event::Link(_) => println!("{event}"),
            _ => {}
        }
    }
    sender.close();
    sender.closed().await;
    Ok(())
}

/// Node discovery in a task of its own (it takes the radio's discovery time); every
/// router or end device found that is not watched yet gets a watcher.
fn spawn_discovery(
    sender: &CommandSender,
    window: Option<Duration>,
    watched: &Arc<Mutex<HashSet<Address64>>>,
) {
    let sender = sender.clone();
    let watched = watched.clone();
    tokio::spawn(async move {
        let found = match sender.discover(window).await {
            Ok(found) => found,
            Err(e) => {
                println!("discovery failed: {e}");
                return;
            }
        };
        let mut watched = watched.lock().unwrap();
        for node in found.nodes {
            if node.device_type == DeviceType::Coordinator {
                continue;
            }
            if watched.insert(node.addr64) {
                println!("discovered {node}");
                spawn_watcher(&sender, node.addr64);
            }
        }
    });
}

/// What a watcher's own tasks tell it.
enum Outcome {
    /// Whether the telemetry was turned on.
    TelemetryOn(Result<(), String>),
    /// The MAV's answer to the status request, or why there was none.
    Probe(Result<String, RequestError>),
}

fn spawn_watcher(sender: &CommandSender, mav: Address64) {
    tokio::spawn(watch(sender.clone(), mav));
}

/// Watches one MAV until the link ends.
async fn watch(sender: CommandSender, mav: Address64) {
    // Every event, not `packets_from(mav)`: the link's events come in line with the
    // packets, so that no reconnection is missed (a `watch_link_state` receiver only
    // sees the latest state, and down-and-up-again between two looks is no change).
    // Taken before the telemetry is turned on: nothing the MAV sends is missed.
    let mut events = sender.subscribe();
    let (outcomes_tx, mut outcomes) = mpsc::channel(4);

    let mut connected = sender.link_state() == LinkState::Connected;
    let mut telemetry_on = false;
    let mut enabling = false;
    let mut probing = false;
    // A MAV that did not answer is not asked again until it has been heard from.
    let mut lost = false;
    let mut heard = false;
    let mut last_heard = Instant::now();
    let mut altitude: Option<f32> = None;
    let mut packets_this_second = 0u32;
    let mut every = tokio::time::interval(Duration::from_secs(1));
    every.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
    let silence = tokio::time::sleep(SILENCE);
    let mut silence = std::pin::pin!(silence);

    loop {
        tokio::select! {
            event = events.next() => match event {
                None => return, // the link has ended
                Some(Event::Packet(rx)) if rx.origin.src64 == mav => {
                    heard = true;
                    last_heard = Instant::now();
                    silence.as_mut().reset(last_heard + SILENCE);
                    packets_this_second += 1;
                    if lost {
                        println!("{mav} back");
                        lost = false;
                    }
                    if let Packet::Telemetry(t) = &rx.packet {
                        altitude = t.value(TelemetryId::Altitude).or(altitude);
                        telemetry_on = true;
                    }
                }
                Some(Event::Link(LinkEvent::Disconnected { .. })) => {
                    connected = false;
                    // Whatever is at the other end next may have forgotten it.
                    telemetry_on = false;
                }
                Some(Event::Link(LinkEvent::Connected { .. } | LinkEvent::Reconnected { .. })) => {
                    connected = true;
                    // The silence while the link was down is not the MAV's.
                    last_heard = Instant::now();
                    silence.as_mut().reset(last_heard + SILENCE);
                }
                Some(_) => {}
            },
            Some(outcome) = outcomes.recv() => match outcome {
                Outcome::TelemetryOn(result) => {
                    enabling = false;
                    match result {
                        Ok(()) => telemetry_on = true,
                        Err(e) => println!("{mav} telemetry not turned on: {e}"),
                    }
                }
                Outcome::Probe(result) => {
                    probing = false;
                    match result {
                        Ok(report) => {
                            println!("{mav} answered: {report}");
                            last_heard = Instant::now();
                            silence.as_mut().reset(last_heard + SILENCE);
                        }
                        // Not the MAV's fault: said by the link's own lines.
                        Err(e) if e.is_link_down() => {}
                        Err(e) => {
                            println!("{mav} lost: {e}");
                            lost = true;
                        }
                    }
                }
            },
            () = &mut silence, if connected && !probing && !lost => {
                let silent = last_heard.elapsed();
                println!("{mav} silent for {:.1} s: asking its landing state", silent.as_secs_f32());
                probing = true;
                // Not again before it has answered or failed.
                silence.as_mut().reset(Instant::now() + Duration::from_secs(3600));
                let sender = sender.clone();
                let outcomes = outcomes_tx.clone();
                tokio::spawn(async move {
                    let result = sender
                        .request_with(mav, StatusRequest::Landing, Some(PROBE_TIMEOUT))
                        .await
                        .map(|report| report.to_string());
                    let _ = outcomes.send(Outcome::Probe(result)).await;
                });
            }
            _ = every.tick() => {
                let silent = last_heard.elapsed();
                if !connected {
                    println!("{mav} unknown: link down");
                } else if lost {
                    println!("{mav} lost: silent for {:.1} s", silent.as_secs_f32());
                } else if !heard && silent < SILENCE {
                    println!("{mav} not heard yet");
                } else if silent >= SILENCE {
                    println!("{mav} silent for {:.1} s", silent.as_secs_f32());
                } else {
                    let altitude = altitude.map_or("?".to_owned(), |a| format!("{a:.2}"));
                    println!(
                        "{mav} ok altitude {altitude} m, {packets_this_second} packets/s, heard {:.1} s ago",
                        silent.as_secs_f32()
                    );
                }
                packets_this_second = 0;
                if connected && !telemetry_on && !enabling {
                    enabling = true;
                    let sender = sender.clone();
                    let outcomes = outcomes_tx.clone();
                    tokio::spawn(async move {
                        let on = Command::telemetry_to_coordinator(true, TelemetryId::Altitude);
                        let result = sender.send(mav, &on).await.map(drop).map_err(|e| e.to_string());
                        let _ = outcomes.send(Outcome::TelemetryOn(result)).await;
                    });
                }
            }
        }
    }
}
