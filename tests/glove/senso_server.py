#!/usr/bin/env python3
"""A one-shot stand-in for the Senso glove's server (tests/glove/cli_test.cmake): listens on a free loopback
port and prints it, sends position packets of the right hand from the address aa:bb:cc:dd:ee:ff until a
command line comes back, writes that line to OUT and exits.

Usage: senso_server.py OUT
"""
import json
import socket
import sys

q = [1.0, 0.0, 0.0, 0.0]
finger = {"quat": q, "ang": [0.0, 0.0], "bend": 0.0}
packet = {"src": "aa:bb:cc:dd:ee:ff", "type": "position",
          "data": {"type": "rh", "palm": {"pos": [0.0, 0.0, 0.0], "quat": q},
                   "fingers": [dict(finger, quat2=q)] + [finger] * 4}}
line = (json.dumps(packet) + "\n").encode()

server = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
server.bind(("127.0.0.1", 0))
server.listen(1)
server.settimeout(10)
print(server.getsockname()[1], flush=True)
conn, _ = server.accept()
conn.settimeout(0.02)
got = b""
for _ in range(500):  # about 10 s at most
    conn.sendall(line)
    try:
        data = conn.recv(4096)
    except socket.timeout:
        continue
    if not data:
        break
    got += data
    if b"\n" in got:
        break
with open(sys.argv[1], "wb") as out:
    out.write(got)
