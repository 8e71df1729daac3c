"""The simulator's end of the serial line: a pseudo-terminal master or a TCP port on 127.0.0.1.

Disconnect and return on a pty: closing the master makes the reader see EIO /
``SerialException`` at once, but the kernel then removes ``/dev/pts/N``, and the next pty may get
another number. So a pty line that will disconnect hands out a *symlink* (in a private temporary
folder, or a path you choose) and re-points it at the new pty when it comes back, the way
``socat``'s ``link=`` does; the reader reopens the same URL. Over TCP the listener is closed too
(a device-server restart: the reader sees "refused") and bound again on the same port.
"""

from __future__ import annotations

import contextlib
import os
import select
import shutil
import socket
import tempfile
import threading
import time
import tty
from pathlib import Path

from station.errors import StationError


def is_pty_link(path: Path) -> bool:
    """True when ``path`` is a symlink to a pseudo-terminal (live or gone): what a simulator
    makes, so one may replace or remove it; never a file someone else put there."""
    try:
        target = os.readlink(path)
    except OSError:
        return False
    return target.startswith(("/dev/pts/", "/dev/tty"))


class Line:
    """One end of the line (``kind`` ``pty`` or ``tcp``): opened, closed for a disconnect,
    opened again on the same URL, written to, read from. Not thread-safe: the simulator holds
    its lock around every call but :meth:`sources`' select."""

    def __init__(self, kind: str, *, link_path: Path | None = None, port: int = 0) -> None:
        self.kind = kind
        self.url = ""
        self.master: int | None = None
        self.slave: int | None = None
        self.link_path = link_path
        self.own_dir: Path | None = None
        self.listener: socket.socket | None = None
        self.conn: socket.socket | None = None
        self.port = port
        self.dropped_bytes = 0
        """Bytes that could not be delivered (the line down, nobody reading)."""
        self.connected = threading.Event()
        """Set while the line is up (a pty open, a TCP port listening)."""

    @classmethod
    def pty(cls, link: str | os.PathLike | bool | None) -> Line:
        """A new pseudo-terminal; ``link`` a path for a stable symlink to it, ``True`` for one
        in a private temporary folder, None for the plain ``/dev/pts/N``."""
        line = cls("pty")
        if link is True:
            line.own_dir = Path(tempfile.mkdtemp(prefix="station-sim-"))
            line.link_path = line.own_dir / "gauge"
        elif link:
            line.link_path = Path(link)
            taken = line.link_path.exists() or line.link_path.is_symlink()
            if taken and not is_pty_link(line.link_path):
                raise StationError(
                    f"{line.link_path} exists and is not a simulator's link (a symlink to "
                    "a pseudo-terminal): remove it",
                    remedy="choose_link_path",
                )
        line.open()
        line.url = str(line.link_path) if line.link_path else os.ttyname(line.slave)
        return line

    @classmethod
    def tcp(cls, port: int) -> Line:
        """A TCP listener on 127.0.0.1:``port`` (0 = a free port)."""
        line = cls("tcp", port=port)
        line.open()
        line.url = f"socket://127.0.0.1:{line.port}"
        return line

    def open(self) -> None:
        """Open the line (again, after a disconnect) on the same URL."""
        if self.kind == "pty":
            self._open_pty()
        else:
            self._listen()

    def _open_pty(self) -> None:
        master, slave = os.openpty()
        # The slave starts cooked (echo, CR->LF): make it raw before anything can touch it.
        tty.setraw(slave)
        os.set_blocking(master, False)
        self.master, self.slave = master, slave
        if self.link_path is not None:
            # A name nobody else uses (symlink() never replaces), renamed over the link at once.
            temporary = self.link_path.with_name(
                f".{self.link_path.name}.{os.getpid()}.{os.urandom(4).hex()}.new"
            )
            os.symlink(os.ttyname(slave), temporary)
            os.replace(temporary, self.link_path)
        self.connected.set()

    def _listen(self) -> None:
        listener = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        listener.bind(("127.0.0.1", self.port))
        listener.listen(1)
        self.listener = listener
        self.port = listener.getsockname()[1]
        self.connected.set()

    def close(self, listener: bool) -> None:
        """Drop the line (the pty, the TCP client, and with ``listener`` the listener)."""
        self.connected.clear()
        if self.link_path is not None and is_pty_link(self.link_path):
            # While down the link must not point at a pty number the kernel may hand to
            # someone else: the reader then sees "no such port" until the return.
            with contextlib.suppress(OSError):
                self.link_path.unlink()
        for name in ("master", "slave"):
            fd = getattr(self, name)
            if fd is not None:
                with contextlib.suppress(OSError):
                    os.close(fd)
                setattr(self, name, None)
        self.drop_client()
        if listener and self.listener is not None:
            with contextlib.suppress(OSError):
                self.listener.close()
            self.listener = None

    def remove(self) -> None:
        """Close for good and remove any link (and private folder) this line made."""
        self.close(listener=True)
        if self.link_path is not None and is_pty_link(self.link_path):
            with contextlib.suppress(OSError):
                self.link_path.unlink()
        if self.own_dir is not None:
            shutil.rmtree(self.own_dir, ignore_errors=True)

    def drop_client(self) -> None:
        """Close the TCP client (another may connect)."""
        if self.conn is not None:
            with contextlib.suppress(OSError):
                self.conn.close()
            self.conn = None

    def has_reader(self) -> bool:
        """True when a reader can be there: a pty, or a TCP client connected."""
        return self.kind == "pty" or self.conn is not None

    def write(self, data: bytes) -> bool:
        """Write all of ``data`` to the reader's side; False (and counted) when it cannot."""
        if self.kind == "tcp":
            if self.conn is None:
                self.dropped_bytes += len(data)
                return False
            try:
                self.conn.sendall(data)
                return True
            except OSError:
                self.drop_client()
                self.dropped_bytes += len(data)
                return False
        if self.master is None:
            self.dropped_bytes += len(data)
            return False
        view = memoryview(data)
        # Nobody drains the pty (no reader yet): wait briefly, then drop, so the server stays
        # responsive; the reader flushes on open anyway.
        deadline = time.monotonic() + 0.1
        while view:
            try:
                written = os.write(self.master, view)
                view = view[written:]
            except BlockingIOError:
                if time.monotonic() > deadline:
                    self.dropped_bytes += len(view)
                    return False
                select.select([], [self.master], [], 0.05)
            except OSError:
                self.dropped_bytes += len(view)
                return False
        return True

    def sources(self) -> list:
        """What to select on for input: the pty master, or the listener and the client."""
        if self.kind == "pty":
            return [self.master] if self.master is not None else []
        return [s for s in (self.listener, self.conn) if s is not None]

    def take(self, source) -> tuple[bytes, bool]:
        """Handle ``source`` found ready: ``(bytes read, a new client connected)``."""
        if self.kind == "pty":
            if source != self.master:
                return b"", False
            try:
                return os.read(self.master, 4096), False
            except (BlockingIOError, OSError):
                return b"", False
        if source is self.listener and self.listener is not None:
            conn, _ = self.listener.accept()
            conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            self.drop_client()  # one client at a time, like a serial line
            self.conn = conn
            return b"", True
        if source is self.conn and self.conn is not None:
            try:
                data = self.conn.recv(4096)
            except OSError:
                data = b""
            if not data:
                self.drop_client()
            return data, False
        return b"", False


__all__ = ["Line", "is_pty_link"]
