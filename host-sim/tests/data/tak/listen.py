"""A TAK client's ear for the tests (host-sim/tests/cot.rs): listen on loopback, decode every
Cursor-on-Target event received with takproto (TAK's own protocol library, from PyPI), print
each as one JSON line.

Usage: python3 listen.py udp COUNT | tcp
Prints the port first; then, for UDP after COUNT datagrams, for TCP when the sender closes the
connection, one JSON object per event (takproto's CotEvent as a dict). Exits 3 after 60 s of
silence.
"""
import json
import socket
import sys

import takproto
from google.protobuf.json_format import MessageToDict

mode = sys.argv[1]
if mode == "udp":
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
else:
    sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
sock.bind(("127.0.0.1", 0))
if mode == "tcp":
    sock.listen(1)
print(sock.getsockname()[1], flush=True)
sock.settimeout(60)
messages = []
try:
    if mode == "udp":
        while len(messages) < int(sys.argv[2]):
            messages.append(sock.recv(65536))
    else:
        conn, _ = sock.accept()
        conn.settimeout(60)
        stream = b""
        while True:
            data = conn.recv(65536)
            if not data:
                break
            stream += data
        # A TAK server's plain-XML input: events back to back.
        messages = [p + b"</event>" for p in stream.split(b"</event>") if p.strip()]
except socket.timeout:
    sys.exit(3)
for m in messages:
    message = takproto.parse_proto(bytearray(m))
    if message is None:
        print(json.dumps({"undecoded": m.decode("utf-8", "replace")}), flush=True)
    else:
        print(json.dumps(MessageToDict(message.cotEvent)), flush=True)
