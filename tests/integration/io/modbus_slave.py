#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""Modbus RTU peer for the tank-level integration test, on one end of a socat pty pair.

  modbus_slave.py PORT normal  SLAVE_ID REG=VALUE...   pymodbus RTU server (independent peer)
  modbus_slave.py PORT silent                           reads requests, never answers
  modbus_slave.py PORT badcrc  SLAVE_ID                 well-formed answers with a wrong CRC
  modbus_slave.py PORT junk                             answers every request with random bytes
Prints "ready" on stdout once it listens.
"""
import os
import random
import sys
import time


def serve_pymodbus(port, slave_id, registers):
    from pymodbus.datastore import (ModbusSequentialDataBlock, ModbusServerContext,
                                    ModbusSlaveContext)
    from pymodbus.server import StartSerialServer
    from pymodbus.transaction import ModbusRtuFramer

    values = [0] * 64
    for address, value in registers.items():
        # pymodbus 3.0's sequential block is off by one: protocol register N lives at index N+1.
        values[address + 1] = value
    store = ModbusSlaveContext(hr=ModbusSequentialDataBlock(0, values),
                               ir=ModbusSequentialDataBlock(0, values))
    context = ModbusServerContext(slaves={slave_id: store}, single=False)
    print("ready", flush=True)
    StartSerialServer(context=context, framer=ModbusRtuFramer, port=port, baudrate=9600,
                      timeout=0.05)


def crc16(data):
    crc = 0xFFFF
    for byte in data:
        crc ^= byte
        for _ in range(8):
            crc = (crc >> 1) ^ 0xA001 if crc & 1 else crc >> 1
    return crc


def serve_raw(port, mode, slave_id):
    import serial

    line = serial.Serial(port, 9600, timeout=0.05)
    print("ready", flush=True)
    rng = random.Random(42)
    while True:
        request = line.read(256)
        if not request or mode == "silent":
            continue
        if mode == "badcrc":
            body = bytes([slave_id, 0x03, 0x02, 0x01, 0x0B])
            crc = crc16(body) ^ 0x5A5A
            line.write(body + bytes([crc & 0xFF, crc >> 8]))
        else:
            line.write(bytes(rng.randrange(256) for _ in range(rng.randrange(1, 12))))


def main():
    port, mode = sys.argv[1], sys.argv[2]
    if mode == "normal":
        registers = {}
        for item in sys.argv[4:]:
            address, value = item.split("=")
            registers[int(address)] = int(value)
        serve_pymodbus(port, int(sys.argv[3]), registers)
    elif mode in ("silent", "badcrc", "junk"):
        serve_raw(port, mode, int(sys.argv[3]) if len(sys.argv) > 3 else 1)
    else:
        sys.exit("modbus_slave.py: unknown mode " + mode)


if __name__ == "__main__":
    main()
