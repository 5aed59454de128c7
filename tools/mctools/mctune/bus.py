"""The CAN bus for `mctune`: a bus given as text (any python-can interface), a canopen Network
on it, and the NMT states of the nodes whose heartbeats are heard there."""

from __future__ import annotations

import logging
import socket
import threading
import time

from mctools.mctune.errors import CommError, InputError

DEFAULT_BUS = "socketcand:127.0.0.1:29536/can0"
DEFAULT_TIMEOUT_S = 1.0

log = logging.getLogger("mctools.mctune")

# NMT: the states a heartbeat reports; the commands as (command specifier, the state they lead to)
NMT_STATES = {0x00: "INITIALISING (boot-up)", 0x04: "STOPPED", 0x05: "OPERATIONAL",
              0x7F: "PRE-OPERATIONAL"}
NMT_COMMANDS = {"start": (0x01, 0x05), "stop": (0x02, 0x04), "pre-op": (0x80, 0x7F),
                "reset": (0x81, 0x00), "reset-comm": (0x82, 0x00)}


def parse_bus_spec(spec: str) -> dict:
    """python-can keyword arguments for SPEC: socketcand:HOST:PORT/CHANNEL, socketcan:CHANNEL,
    virtual:NAME or INTERFACE:CHANNEL, each optionally followed by ,key=value options
    (e.g. pcan:PCAN_USBBUS1,bitrate=500000)."""
    head, *opts = spec.split(",")
    interface, sep, rest = head.partition(":")
    if not sep or not interface or not rest:
        raise InputError(f"bus {spec!r}: expected INTERFACE:CHANNEL (socketcand:HOST:PORT/CHANNEL, "
                         f"socketcan:can0, virtual:NAME)")
    kwargs: dict = {"interface": interface}
    if interface == "socketcand":
        hostport, slash, channel = rest.partition("/")
        host, colon, port = hostport.rpartition(":")
        if not slash or not colon or not host or not channel or not port.isdigit():
            raise InputError(f"bus {spec!r}: expected socketcand:HOST:PORT/CHANNEL, "
                             f"e.g. {DEFAULT_BUS}")
        kwargs.update(host=host.strip("[]"), port=int(port), channel=channel)
    else:
        kwargs["channel"] = rest
    for opt in opts:
        key, eq, value = opt.partition("=")
        if not eq or not key:
            raise InputError(f"bus {spec!r}: option {opt!r} is not key=value")
        try:
            kwargs[key] = int(value, 0)
        except ValueError:
            kwargs[key] = {"true": True, "false": False}.get(value.lower(), value)
    return kwargs


class HeartbeatWatch:
    """A python-can listener remembering the last heartbeat / boot-up (0x700 + id) per node."""

    def __init__(self):
        self.nodes: dict[int, tuple[int, float]] = {}
        self.cond = threading.Condition()
        self.started = time.monotonic()

    def on_message_received(self, msg):
        if msg.is_error_frame or msg.is_remote_frame or msg.is_extended_id:
            return
        if 0x701 <= msg.arbitration_id <= 0x77F and len(msg.data) >= 1:
            with self.cond:
                self.nodes[msg.arbitration_id - 0x700] = (msg.data[0] & 0x7F, time.monotonic())
                self.cond.notify_all()

    def __call__(self, msg):  # can.Listener protocol of some python-can versions
        self.on_message_received(msg)

    def stop(self):
        pass

    def on_error(self, exc):
        pass

    def wait(self, node: int | None, timeout: float) -> bool:
        """Wait until node (None: any node) has been heard, at most timeout s."""
        def heard():
            return (node in self.nodes) if node is not None else bool(self.nodes)

        with self.cond:
            return self.cond.wait_for(heard, timeout)

    def state(self, node: int) -> int | None:
        with self.cond:
            return self.nodes[node][0] if node in self.nodes else None

    def seen(self) -> list[int]:
        with self.cond:
            return sorted(self.nodes)


def open_network(spec: str, timeout: float = DEFAULT_TIMEOUT_S):
    """A connected canopen.Network on SPEC and its HeartbeatWatch."""
    import can
    import canopen

    kwargs = parse_bus_spec(spec)
    if kwargs["interface"] == "socketcand":
        # python-can retries a refused connection for 10 s: find out at once.
        try:
            socket.create_connection((kwargs["host"], kwargs["port"]), timeout=max(timeout, 1.0)).close()
        except OSError as exc:
            raise CommError(f"cannot open bus {spec}: {kwargs['host']}:{kwargs['port']}: "
                            f"{exc.strerror or exc} (is socketcand, or mcsim --can, running there?)") from None
    watch = HeartbeatWatch()
    network = canopen.Network()
    network.NOTIFIER_CYCLE = 0.1   # a quick disconnect (the notifier thread wakes this often)
    network.NOTIFIER_SHUTDOWN_TIMEOUT = 1.0
    network.listeners.append(watch)
    try:
        network.connect(**kwargs)
    except (can.CanError, OSError, ValueError, TypeError, ImportError, NotImplementedError) as exc:
        raise CommError(f"cannot open bus {spec}: {exc}") from None
    return network, watch


def close_network(network) -> None:
    try:
        network.disconnect()
    except Exception as exc:  # noqa: BLE001 - closing must not hide the command's result
        log.debug("disconnect: %s", exc)
