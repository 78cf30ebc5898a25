"""A ground station written with Digi's xbee-python library (digi-xbee 1.5.0).

Opens the XBee on PORT as xbee-python opens a real module (it asks the API mode, then
HV, VR, SH, SL, NI, MY and CE), then runs the steps given, printing one line a step:

    send HEX      send the bytes to MAV; prints `delivered STATUS` or `failed STATUS`
    send-to ADDR HEX
                  the same to another 64-bit address
    read N        read N messages; prints `rx SRC64 HEX` for each
    name NAME     set MAV's node identifier (NI) by a remote AT command; prints `named NI`
                  with the NI read back
    discover NAME find the radio named NAME by node discovery (ND); prints
                  `found ADDR64 NI` or `not found`

Usage: xbee_python_ground.py PORT MAV STEP...
"""

import sys

from digi.xbee.devices import RemoteZigBeeDevice, ZigBeeDevice
from digi.xbee.exception import TimeoutException, TransmitException
from digi.xbee.models.address import XBee16BitAddress, XBee64BitAddress

READ_TIMEOUT_S = 20


def main(port, mav, steps):
    device = ZigBeeDevice(port, 115200)
    device.open()
    try:
        print(
            "open",
            device.get_64bit_addr(),
            device.get_protocol().name,
            device.get_role().name,
            device.operating_mode.name,
            flush=True,
        )
        while steps:
            step = steps.pop(0)
            if step in ("send", "send-to"):
                to = steps.pop(0) if step == "send-to" else mav
                send(device, to, bytes.fromhex(steps.pop(0)))
            elif step == "read":
                for _ in range(int(steps.pop(0))):
                    try:
                        message = device.read_data(READ_TIMEOUT_S)
                    except TimeoutException:
                        print("timeout", flush=True)
                        return 1
                    print(
                        "rx",
                        message.remote_device.get_64bit_addr(),
                        message.data.hex(),
                        flush=True,
                    )
            elif step == "name":
                remote = RemoteZigBeeDevice(device, XBee64BitAddress.from_hex_string(mav))
                remote.set_node_id(steps.pop(0))
                remote.read_device_info(init=True)
                print("named", remote.get_node_id(), flush=True)
            elif step == "discover":
                found = device.get_network().discover_device(steps.pop(0))
                if found is None:
                    print("not found", flush=True)
                else:
                    print("found", found.get_64bit_addr(), found.get_node_id(), flush=True)
            else:
                raise ValueError(f"unknown step {step!r}")
    finally:
        device.close()
    return 0


def send(device, to, data):
    try:
        status = device.send_data_64_16(
            XBee64BitAddress.from_hex_string(to), XBee16BitAddress.UNKNOWN_ADDRESS, data
        )
        print("delivered", status.transmit_status.name, flush=True)
    except TransmitException as error:
        print("failed", error.status.name, flush=True)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], sys.argv[2], sys.argv[3:]))
