#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""Replays one board's recorded broker messages as many boards, for the cab's figures.

usage: fleet-replay.py PORT MACHINE BOARDS SECONDS RECORDING
RECORDING holds lines "TIME TOPIC PAYLOAD" (mosquitto_sub -v behind a time stamp) of one
board, weedspray/<machine>/<board>/<leaf>; each line is published, retained, for boards
r1..rBOARDS at its recorded offset, looped until SECONDS have passed. A minimal MQTT 3.1.1
client on a plain socket (QoS 0): no library beyond Python's own. Prints the messages sent.
"""
import socket
import sys
import time


def remaining_length(n):
    out = bytearray()
    while True:
        byte, n = n % 128, n // 128
        out.append(byte | (0x80 if n else 0))
        if not n:
            return bytes(out)


def packet(kind, body):
    return bytes([kind]) + remaining_length(len(body)) + body


def text(value):
    data = value.encode()
    return len(data).to_bytes(2, "big") + data


def main(port, machine, boards, seconds, recording):
    lines = []
    for line in open(recording, encoding="utf-8"):
        stamp, topic, payload = line.rstrip("\n").split(" ", 2)
        leaf = topic.split("/")[-1]
        lines.append((float(stamp), leaf, payload.encode()))
    start_of_recording = lines[0][0]
    span = lines[-1][0] - start_of_recording + 0.25
    sock = socket.create_connection(("127.0.0.1", port))
    sock.sendall(packet(0x10, text("MQTT") + bytes([4, 0x02, 0, 60]) + text("fleet-replay")))
    sock.recv(4)  # CONNACK
    started = time.monotonic()
    sent = 0
    loop = 0
    while True:
        for stamp, leaf, payload in lines:
            due = started + loop * span + (stamp - start_of_recording)
            if due - started > seconds:
                sock.sendall(packet(0xE0, b""))  # DISCONNECT
                print(sent)
                return
            delay = due - time.monotonic()
            if delay > 0:
                time.sleep(delay)
            for board in range(1, boards + 1):
                topic = f"weedspray/{machine}/r{board}/{leaf}"
                sock.sendall(packet(0x31, text(topic) + payload))
                sent += 1
        loop += 1


if __name__ == "__main__":
    main(int(sys.argv[1]), sys.argv[2], int(sys.argv[3]), float(sys.argv[4]), sys.argv[5])
