//! `mcp-gs ports`: list the serial ports present.

use clap::Args;
use serialport::SerialPortType;

use crate::Failure;

/// Arguments of `ports`.
#[derive(Debug, Args)]
pub(crate) struct PortsArgs {}

/// Runs `ports`.
pub(crate) fn run(_args: PortsArgs) -> Result<(), Failure> {
    let ports = serialport::available_ports()
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
