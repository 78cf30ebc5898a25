//! `mcp-gs ports`: list the serial ports present.

use std::path::Path;

use clap::Args;
use serialport::{SerialPortInfo, SerialPortType};

use crate::Failure;

/// Arguments of `ports`.
#[derive(Debug, Args)]
pub(crate) struct PortsArgs {}

/// Where Linux lists its terminal devices, which `serialport` scans.
const SYS_TTY: &str = "/sys/class/tty";

/// Runs `ports`.
pub(crate) fn run(_args: PortsArgs) -> Result<(), Failure> {
    let ports = available_ports(Path::new(SYS_TTY))
        .map_err(|e| Failure::new(Failure::OTHER, format!("cannot list serial ports: {e}")))?;
    let ports = without_dial_in_twins(ports);
    if ports.is_empty() {
        out!("no serial ports found");
    }
    for port in ports {
        let detail = match port.port_type {
            SerialPortType::UsbPort(usb) => {
                let mut s = format!("usb {:04x}:{:04x}", usb.vid, usb.pid);
                for part in [
                    usb.manufacturer,
                    usb.product,
                    usb.serial_number.map(|s| format!("serial {s}")),
                ]
                .into_iter()
                .flatten()
                {
                    s.push_str(", ");
                    s.push_str(&part);
                }
                s
            }
            SerialPortType::PciPort => "pci".into(),
            SerialPortType::BluetoothPort => "bluetooth".into(),
            SerialPortType::Unknown => "unknown type".into(),
        };
        out!("serial:{}\t{detail}", port.port_name);
    }
    Ok(())
}

/// The serial ports present. On Linux, `serialport` panics where `sys_tty` cannot be
/// read (a container without sysfs): that is an error here instead, with its cause.
fn available_ports(sys_tty: &Path) -> Result<Vec<SerialPortInfo>, String> {
    if cfg!(target_os = "linux") {
        std::fs::read_dir(sys_tty)
            .map_err(|e| format!("cannot read {}: {e} (is sysfs mounted?)", sys_tty.display()))?;
    }
    serialport::available_ports().map_err(|e| e.to_string())
}

/// `ports` without the dial-in twin of a call-out device: macOS lists each port twice,
/// as `/dev/tty.NAME` (dial-in: opening it may wait for the carrier signal, which an
/// XBee adapter does not raise) and `/dev/cu.NAME` (call-out), the one to use. The
/// `tty.` one is left out when its `cu.` twin is listed.
fn without_dial_in_twins(ports: Vec<SerialPortInfo>) -> Vec<SerialPortInfo> {
    let call_out = |name: &str| {
        name.strip_prefix("/dev/tty.")
            .map(|rest| format!("/dev/cu.{rest}"))
    };
    let names: Vec<String> = ports.iter().map(|p| p.port_name.clone()).collect();
    ports
        .into_iter()
        .filter(|port| !call_out(&port.port_name).is_some_and(|cu| names.contains(&cu)))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_port_listed_twice_on_macos_is_listed_by_its_call_out_name() {
        let port = |name: &str| SerialPortInfo {
            port_name: name.to_owned(),
            port_type: SerialPortType::Unknown,
        };
        let listed = without_dial_in_twins(vec![
            port("/dev/tty.usbserial-A1"),
            port("/dev/cu.usbserial-A1"),
            port("/dev/tty.Bluetooth-Incoming-Port"),
            port("/dev/ttyUSB0"),
            port("COM3"),
        ]);
        let names: Vec<_> = listed.iter().map(|p| p.port_name.as_str()).collect();
        assert_eq!(
            names,
            [
                "/dev/cu.usbserial-A1",
                "/dev/tty.Bluetooth-Incoming-Port",
                "/dev/ttyUSB0",
                "COM3"
            ]
        );
    }

    // It reads Linux's sysfs.
    #[cfg(target_os = "linux")]
    #[test]
    fn a_missing_sysfs_is_an_error_not_a_panic() {
        let err = available_ports(Path::new("/nonexistent/sys/class/tty")).unwrap_err();
        assert_eq!(
            err,
            "cannot read /nonexistent/sys/class/tty: No such file or directory (os error 2) \
             (is sysfs mounted?)"
        );
    }
}
