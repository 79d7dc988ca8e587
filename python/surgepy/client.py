"""Client side of surge's live stream and control socket (the wire format is docs/protocol.md).

    import zmq
    from surgepy import client as surge_client
    sub = surge_client.subscribe("tcp://127.0.0.1:5555", ["state", "stats"])
    topic, header, arrays = surge_client.receive(sub)        # arrays["x_m"] is a numpy array
    ctl = surge_client.Control("tcp://127.0.0.1:5556")
    ctl.request({"cmd": "set", "key": "fluid.viscosity_m2ps", "value": 0.006})

A run started with --curve-key/--curve-clients admits only clients with an allowed key (docs/protocol.md):
    keys = surge_client.curve_keys("run.pub", "me.key")      # the run's public key, this client's key pair
    ctl = surge_client.Control("tcp://host:5556", curve=keys)
"""
import json

import numpy as np
import zmq

SCHEMA = 1
DTYPES = {"f64": "<f8", "f32": "<f4", "i32": "<i4", "u8": "u1"}


class ProtocolError(Exception):
    """A message or reply that does not follow docs/protocol.md; the message says what is wrong."""


def _is_number(value):
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _is_field(field):
    """A well-formed entry of a header's fields: {"name", "dtype" (one of DTYPES), "components" >= 1, ...}."""
    return (isinstance(field, dict) and isinstance(field.get("name"), str) and isinstance(field.get("dtype"), str)
            and field["dtype"] in DTYPES and isinstance(field.get("components"), int) and field["components"] >= 1)


def curve_keys(server_public_path, client_key_path):
    """(server public key, client public key, client secret key) from key files made by `surge keygen` (or
    pyzmq's zmq.auth); ValueError naming the file when one cannot be read or lacks a key."""
    import zmq.auth
    keys = []
    for path, secret in ((server_public_path, False), (client_key_path, True)):
        try:
            public, secret_key = zmq.auth.load_certificate(path)
        except (OSError, ValueError) as e:
            raise ValueError("%s: %s" % (path, e))
        if secret and not secret_key:
            raise ValueError("%s holds no secret-key: give this client's .key file, not its .pub" % path)
        keys += [public, secret_key] if secret else [public]
    return tuple(keys)


def _secure(sock, curve):
    if curve is not None:
        sock.curve_serverkey, sock.curve_publickey, sock.curve_secretkey = curve


def subscribe(endpoint, topics, context=None, latest_only=True, curve=None):
    """A SUB socket connected to a surge publisher. latest_only keeps a short receive queue (the publisher
    drops what a slow client cannot take); pair it with receive_latest() to always show the newest state.
    curve: curve_keys(...) for a run that uses CURVE."""
    sock = (context or zmq.Context.instance()).socket(zmq.SUB)
    _secure(sock, curve)
    if latest_only:
        sock.setsockopt(zmq.RCVHWM, 2)
    sock.setsockopt(zmq.IPV6, 1)  # for tcp://[::1]:PORT; IPv4 addresses still work
    sock.connect(endpoint)
    for topic in topics:
        sock.setsockopt(zmq.SUBSCRIBE, topic.encode())
    return sock


def decode(parts):
    """Decodes one multipart message: (topic, header dict, {field name: numpy array})."""
    if len(parts) < 2:
        raise ProtocolError("a message has a topic frame and a JSON header frame, got %d frames" % len(parts))
    try:
        topic = parts[0].decode("ascii")
        header = json.loads(parts[1])
    except ValueError as e:
        raise ProtocolError("a topic frame in ASCII and a JSON header frame expected (%s)" % e)
    if not isinstance(header, dict):
        raise ProtocolError("%s: the header is not a JSON object" % topic)
    if header.get("schema") != SCHEMA:
        raise ProtocolError("schema %r, this client reads schema %d" % (header.get("schema"), SCHEMA))
    if not (_is_number(header.get("step")) and _is_number(header.get("time_s"))):
        raise ProtocolError("%s: the header has no step and time_s" % topic)
    fields = header.get("fields", [])
    if not (isinstance(fields, list) and all(_is_field(f) for f in fields)
            and (not fields or isinstance(header.get("count"), int) and header["count"] >= 0)):
        raise ProtocolError("%s: malformed fields or count in the header" % topic)
    if len(parts) != 2 + len(fields):
        raise ProtocolError("%s: header lists %d fields but %d array frames follow"
                            % (topic, len(fields), len(parts) - 2))
    arrays = {}
    for field, data in zip(fields, parts[2:]):
        dtype = np.dtype(DTYPES[field["dtype"]])
        if len(data) != header["count"] * field["components"] * dtype.itemsize:
            raise ProtocolError("%s: field %s has %d bytes, expected %d values of %s"
                                % (topic, field["name"], len(data), header["count"] * field["components"],
                                   field["dtype"]))
        a = np.frombuffer(data, dtype=dtype)
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

    def __init__(self, endpoint, timeout_s=5.0, context=None, curve=None):
        self.endpoint, self.timeout_ms, self.curve = endpoint, int(1000 * timeout_s), curve
        self.context = context or zmq.Context.instance()
        self._open()

    def _open(self):
        self.sock = self.context.socket(zmq.REQ)
        self.sock.setsockopt(zmq.LINGER, 0)
        _secure(self.sock, self.curve)
        self.sock.setsockopt(zmq.IPV6, 1)
        self.sock.connect(self.endpoint)

    def request(self, message):
        """Sends a dict (as JSON) or raw bytes; returns the reply as a dict (ProtocolError if it is not a JSON
        object)."""
        self.sock.send(message if isinstance(message, bytes) else json.dumps(message).encode())
        if not self.sock.poll(self.timeout_ms):
            self.sock.close()
            self._open()
            raise TimeoutError("no reply from %s within %.1f s" % (self.endpoint, self.timeout_ms / 1000))
        raw = self.sock.recv()
        try:
            reply = json.loads(raw)
        except ValueError:
            reply = None
        if not isinstance(reply, dict):
            raise ProtocolError("the reply is not a JSON object: %r" % raw[:100])
        return reply

    def close(self):
        self.sock.close()
