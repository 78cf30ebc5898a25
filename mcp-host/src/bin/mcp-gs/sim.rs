//! `mcp-gs sim`: simulated MAVs behind a virtual XBee network on a link.

use std::time::Duration;

use clap::Args;
use mcp_host::Link;
use mcp_host::radio::MAX_UNICAST_FRAGMENTED;
use mcp_host::sim::{SimOptions, Simulator, fleet_addresses};
use xbee_api::Address64;

use crate::Failure;
use crate::radio::{
    NamedLink, NetArgs, RadioModeArg, check_distinct, describe_node, parse_address, parse_duration,
    watch,
};

/// Arguments of `sim`.
#[derive(Debug, Args)]
#[command(after_long_help = SIM_HELP)]
pub(crate) struct SimArgs {
    /// Where the ground station connects: the link of the network's coordinator
    /// (`pty`, `tcp-listen:127.0.0.1:9750`, `serial:/dev/pts/5`...).
    #[arg(long, value_name = "LINK", value_parser = crate::link_args::parse_link)]
    link: Link,
    /// A simulated MAV's 64-bit address (repeat for more). Default 0013A20040B599B9.
    #[arg(long = "address", value_name = "ADDR", value_parser = parse_address)]
    addresses: Vec<Address64>,
    /// Number of MAVs, no fewer than the `--address` options: the given addresses, then
    /// the known MAVs 0013A20040B599B9, 0013A20040B599BF, 0013A20040B599BD,
    /// 0013A20040B599B8, then made-up ones.
    #[arg(long, value_name = "N", value_parser = crate::whole_number(1u16, 4096))]
    mavs: Option<u16>,
    /// API mode of the link (what the ground station's XBee is set to): 1, 2, or 0 for
    /// a radio in transparent mode (AP=0) as XBee modules leave the factory, which
    /// `mcp-gs setup` puts into API mode.
    #[arg(long, default_value = "1", value_name = "0|1|2")]
    api_mode: RadioModeArg,
    /// Drop commands whose frame is longer than N bytes, as the deployed MAV's 60-byte
    /// UART receive buffer does (default: no limit). At least 19, the smallest command's
    /// frame.
    #[arg(long, value_name = "N", value_parser = parse_rx_buffer)]
    rx_buffer: Option<usize>,
    #[command(flatten)]
    net: NetArgs,
    /// Print every delivery, not only connections and failures.
    #[arg(long, short)]
    verbose: bool,
    /// Stop after this many seconds; 0, the default, runs until Ctrl-C.
    #[arg(long, value_name = "SECONDS", value_parser = parse_duration)]
    duration: Option<Duration>,
}

/// The wire length of the smallest command frame a MAV receives: a Receive Packet (frame
/// data 12 bytes and the payload) carrying a 3-byte command (a status request, landing
/// or controllers), with the start delimiter, the length and the checksum. A receive
/// buffer smaller than this drops every command.
const SMALLEST_COMMAND_FRAME: usize = 4 + 12 + 3;

/// `--rx-buffer`: a number of bytes no smaller than the smallest command's frame.
fn parse_rx_buffer(s: &str) -> Result<usize, String> {
    let n: usize = s
        .parse()
        .map_err(|_| format!("expected a number of bytes, got `{s}`"))?;
    if n < SMALLEST_COMMAND_FRAME {
        return Err(format!(
            "a receive buffer of {n} bytes drops every command: the smallest command's \
             frame takes {SMALLEST_COMMAND_FRAME} bytes (the deployed MAV's buffer is {})",
            mcp_host::sim::MAV_RX_BUFFER
        ));
    }
    Ok(n)
}

const SIM_HELP: &str = "\
Each MAV answers commands as the deployed MAVs do (status requests with reports, trajectory \
set with a trajectory report, unsolicited landing and controller reports), sends 20 Hz \
telemetry of the enabled ids, and flies a small model: landing on -> landing -> on_ground, \
landing off -> take_off -> stabilization -> flight, the mpc controller follows the \
trajectory by MAV time. The MAVs are XBee nodes in API mode 1 behind a virtual network \
whose coordinator is --link: the ground station sees Transmit Statuses and Receive \
Packets as from its own XBee. Unicast payloads go up to 255 bytes (fragmentation, as MCP \
packets need; --max-unicast 84 emulates radios without it). Unlike the deployed MAVs, \
whose 60-byte UART receive buffer drops longer frames (a trajectory of more than 2 \
waypoints, a message of more than 43 bytes), they take commands of any size unless \
--rx-buffer 60 says otherwise. Faults options as in `mcp-gs radio`.

Example: mcp-gs sim --link pty --mavs 2   (then connect a ground station to the printed path;
on Windows, which has no pseudo-terminals: --link tcp-listen:127.0.0.1:9750, and the
ground station's --link tcp:127.0.0.1:9750)";

/// How many MAVs' addresses a line of the fleet's list holds (as `0013a20040b599b9/7d84`).
const MAVS_A_LINE: usize = 4;

/// Runs `sim`.
pub(crate) async fn run(args: SimArgs) -> Result<(), Failure> {
    crate::hints::check_serial_path(&args.link, false)?;
    // Checked as given: the defaults added below never repeat an address.
    check_distinct(&args.addresses, "simulated MAV")?;
    let mut addresses = args.addresses.clone();
    let wanted = args.mavs.map_or(addresses.len().max(1), usize::from);
    if wanted < addresses.len() {
        return Err(Failure::input(format!(
            "--mavs {wanted} is fewer than the {} --address options given: drop --mavs, or \
             raise it to {} or more",
            addresses.len(),
            addresses.len()
        )));
    }
    for address in fleet_addresses(wanted + addresses.len()) {
        if addresses.len() >= wanted {
            break;
        }
        if !addresses.contains(&address) {
            addresses.push(address);
        }
    }
    addresses.truncate(wanted);
    args.net.check_nodes(&addresses, "simulated MAV")?;
    let config = args.net.config(MAX_UNICAST_FRAGMENTED)?;
    // Said once the links are open: a link that cannot be opened is the one line.
    let described = config.clone();
    let options = SimOptions {
        rx_buffer: args.rx_buffer,
        coordinator_transparent: args.api_mode.transparent,
    };
    let mode = args.api_mode.api_mode;
    let sim = Simulator::start_with(&args.link, mode, &addresses, config, options)
        .await
        .map_err(|e| crate::hints::network_failure(e, &args.link))?;
    args.net.describe(&described);
    let events = sim.network().subscribe();
    for mav in sim.mavs() {
        if let Some(faults) = args.net.faults_of(mav.addr64) {
            sim.network().set_faults(mav.addr64, Some(faults));
        }
    }
    if let Some(faults) = args.net.faults_of(Address64::COORDINATOR) {
        sim.network()
            .set_faults(Address64::COORDINATOR, Some(faults));
    }
    out!(
        "{}",
        describe_node(
            "ground station link: coordinator",
            sim.coordinator(),
            &args.link
        )
    );
    let list: Vec<String> = sim
        .mavs()
        .iter()
        .map(|m| format!("{}/{}", m.addr64, m.addr16))
        .collect();
    if list.len() <= MAVS_A_LINE {
        out!(
            "simulating {}: {}",
            crate::counted(list.len() as u64, "MAV"),
            list.join(", ")
        );
    } else {
        // A fleet is listed a few to a line, not on one line of thousands of bytes.
        out!("simulating {}:", crate::counted(list.len() as u64, "MAV"));
        for line in list.chunks(MAVS_A_LINE) {
            out!("  {}", line.join(", "));
        }
    }
    // The MAVs are in the process: the ground station's link is the one that can end.
    let links = [NamedLink::new(
        Address64::COORDINATOR,
        "the ground station's link",
        &args.link,
    )];
    watch(
        sim.network(),
        events,
        &args.net,
        args.verbose,
        args.duration,
        &links,
    )
    .await
}
