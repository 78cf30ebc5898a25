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

// Its only test reads Linux's sysfs.
#[cfg(all(test, target_os = "linux"))]
mod tests {
    use super::*;

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
