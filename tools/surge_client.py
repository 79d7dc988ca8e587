"""Client side of surge's live stream and control socket (the wire format is docs/protocol.md).

    import zmq, surge_client
    sub = surge_client.subscribe("tcp://127.0.0.1:5555", ["state", "stats"])
    topic, header, arrays = surge_client.receive(sub)        # arrays["x_m"] is a numpy array
    ctl = surge_client.Control("tcp://127.0.0.1:5556")
    ctl.request({"cmd": "set", "key": "fluid.viscosity_m2ps", "value": 0.006})
"""
import json

import numpy as np
import zmq

SCHEMA = 1
DTYPES = {"f64": "<f8", "f32": "<f4", "i32": "<i4", "u8": "u1"}


class ProtocolError(Exception):
    pass


def subscribe(endpoint, topics, context=None, latest_only=True):
    """A SUB socket connected to a surge publisher. latest_only keeps a short receive queue (the publisher
    drops what a slow client cannot take); pair it with receive_latest() to always show the newest state."""
    sock = (context or zmq.Context.instance()).socket(zmq.SUB)
    if latest_only:
        sock.setsockopt(zmq.RCVHWM, 2)
    sock.connect(endpoint)
    for topic in topics:
        sock.setsockopt(zmq.SUBSCRIBE, topic.encode())
    return sock


def decode(parts):
    """Decodes one multipart message: (topic, header dict, {field name: numpy array})."""
    if len(parts) < 2:
        raise ProtocolError("a message has a topic frame and a JSON header frame, got %d frames" % len(parts))
    topic = parts[0].decode()
    header = json.loads(parts[1])
    if header.get("schema") != SCHEMA:
        raise ProtocolError("schema %r, this client reads schema %d" % (header.get("schema"), SCHEMA))
    fields = header.get("fields", [])
    if len(parts) != 2 + len(fields):
        raise ProtocolError("%s: header lists %d fields but %d array frames follow"
                            % (topic, len(fields), len(parts) - 2))
    arrays = {}
    for field, data in zip(fields, parts[2:]):
        a = np.frombuffer(data, dtype=DTYPES[field["dtype"]])
        if a.size != header["count"] * field["components"]:
            raise ProtocolError("%s: field %s has %d values, expected %d"
                                % (topic, field["name"], a.size, header["count"] * field["components"]))
        arrays[field["name"]] = a.reshape(-1, field["components"]) if field["components"] > 1 else a
    return topic, header, arrays


def receive(sock, timeout_ms=None):
    """The next message, decoded; None after timeout_ms without one."""
    if timeout_ms is not None and not sock.poll(timeout_ms):
        return None
    return decode(sock.recv_multipart())


def receive_latest(sock, timeout_ms=None):
    """Waits for a message, then drains the queue and returns the newest message of each topic
    ({topic: (header, arrays)}); ZMQ_CONFLATE cannot do this for multipart messages."""
    first = receive(sock, timeout_ms)
    if first is None:
        return {}
    latest = {first[0]: first[1:]}
    while sock.poll(0):
        topic, header, arrays = decode(sock.recv_multipart())
        latest[topic] = (header, arrays)
    return latest


class Control:
    """A REQ client of the control socket; a request without a reply within timeout_s raises TimeoutError
    and the socket is replaced (a REQ socket cannot send again before it has its reply)."""

    def __init__(self, endpoint, timeout_s=5.0, context=None):
        self.endpoint, self.timeout_ms = endpoint, int(1000 * timeout_s)
        self.context = context or zmq.Context.instance()
        self._open()

    def _open(self):
        self.sock = self.context.socket(zmq.REQ)
        self.sock.setsockopt(zmq.LINGER, 0)
        self.sock.connect(self.endpoint)

    def request(self, message):
        """Sends a dict (as JSON) or raw bytes; returns the reply as a dict."""
        self.sock.send(message if isinstance(message, bytes) else json.dumps(message).encode())
        if not self.sock.poll(self.timeout_ms):
            self.sock.close()
            self._open()
            raise TimeoutError("no reply from %s within %.1f s" % (self.endpoint, self.timeout_ms / 1000))
        return json.loads(self.sock.recv())

    def close(self):
        self.sock.close()
