"""The local XBee of a ground station, framed by Digi's xbee-python library (1.5.0).

Opens PORT (the ground station's pseudo-terminal) in API mode MODE (1 or 2) and plays
the radio with xbee-python's own frame reader (`XBeeSerialPort.wait_for_frame`), frame
parser (`factory.build_frame`) and frame builders, printing one line a frame it gets:

- at start, a Modem Status "coordinator started";
- an AT Command `AP` is answered with MODE (`at AP`);
- a Transmit Request is printed as `tx FRAME_ID DST64 HEX`, answered with a Transmit
  Status "success" from 16-bit address 7D84 (0x7D is escaped in mode 2), then with a
  Receive Packet from DST64 carrying the next ANSWER, if any.

After as many Transmit Requests as there are ANSWERs (at least one) it waits for the
end of its standard input, then stops; so it stops early only if something failed.

Usage: xbee_python_radio.py PORT MODE ANSWER_HEX...
"""

import sys
import time

from digi.xbee.models.address import XBee16BitAddress
from digi.xbee.models.mode import OperatingMode
from digi.xbee.models.options import ReceiveOptions
from digi.xbee.models.status import (
    ATCommandStatus,
    DiscoveryStatus,
    ModemStatus,
    TransmitStatus,
)
from digi.xbee.packets import factory
from digi.xbee.packets.common import (
    ATCommPacket,
    ATCommResponsePacket,
    ModemStatusPacket,
    ReceivePacket,
    TransmitPacket,
    TransmitStatusPacket,
)
from digi.xbee.serial import XBeeSerialPort

DEADLINE_S = 30
SOURCE16 = XBee16BitAddress.from_hex_string("7D84")


def main(port_path, mode_number, answers):
    mode = {"1": OperatingMode.API_MODE, "2": OperatingMode.ESCAPED_API_MODE}[mode_number]
    escaped = mode == OperatingMode.ESCAPED_API_MODE
    answers = [bytearray.fromhex(a) for a in answers]
    port = XBeeSerialPort(9600, port_path, timeout=0.2)
    port.open()

    def write(packet):
        port.write(packet.output(escaped=escaped))

    write(ModemStatusPacket(ModemStatus.COORDINATOR_STARTED))
    deadline = time.monotonic() + DEADLINE_S
    while answers:
        if time.monotonic() > deadline:
            print("timeout", flush=True)
            return 1
        raw = port.wait_for_frame(mode)
        if raw is None:
            continue
        packet = factory.build_frame(raw, mode)
        if isinstance(packet, ATCommPacket):
            print("at", packet.command, flush=True)
            value = bytearray([int(mode_number)]) if packet.command == "AP" else None
            status = ATCommandStatus.OK if value else ATCommandStatus.INVALID_COMMAND
            write(ATCommResponsePacket(packet.frame_id, packet.command, status, value))
        elif isinstance(packet, TransmitPacket):
            print("tx", packet.frame_id, packet.x64bit_dest_addr, packet.rf_data.hex(), flush=True)
            write(
                TransmitStatusPacket(
                    packet.frame_id,
                    SOURCE16,
                    0,
                    TransmitStatus.SUCCESS,
                    DiscoveryStatus.NO_DISCOVERY_OVERHEAD,
                )
            )
            write(
                ReceivePacket(
                    packet.x64bit_dest_addr,
                    SOURCE16,
                    ReceiveOptions.PACKET_ACKNOWLEDGED.value,
                    answers.pop(0),
                )
            )
        else:
            print("other", packet.get_frame_type().name, flush=True)
    sys.stdin.read()
    port.close()
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], sys.argv[2], sys.argv[3:]))
