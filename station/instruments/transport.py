"""Opening gauge ports by URL, and the sentences a technician reads when that fails.

Every port is opened with ``serial.serial_for_url`` so a device path (``/dev/ttyUSB0``), a stable
``/dev/serial/by-id/...`` path, a serial device server (``rfc2217://host:port``, e.g. ser2net), a
raw TCP bridge (``socket://host:port``) and a USB id (``hwgrep://VID:PID``) all work the same way.
pyserial reports most failures as one ``SerialException`` whose text varies by handler; this module
turns them into :class:`~station.errors.StationError` sentences that say what to do.
"""

from __future__ import annotations

import errno
import os
import re
import stat
import termios
from dataclasses import dataclass
from pathlib import Path

import serial
from serial.tools import list_ports as serial_list_ports

from station.errors import StationError
from station.instruments.base import SerialSettings

NETWORK_SCHEMES = ("socket", "rfc2217")
"""URL schemes that reach a device over TCP: no local lock applies to them."""

_BY_ID_FOLDER = Path("/dev/serial/by-id")

PSEUDO_TERMINAL_MAJORS = range(136, 144)
"""Linux's major device numbers of the pseudo-terminals a program opens (``/dev/pts/N``)."""


@dataclass(frozen=True)
class PortInfo:
    """One serial port the operating system lists, as ``station ports`` shows it."""

    device: str
    description: str
    by_id: str | None
    """The stable ``/dev/serial/by-id/...`` link to this port, when udev made one."""
    vid_pid: str | None
    """USB vendor and product id as ``vvvv:pppp`` (the form ``hwgrep://`` accepts)."""
    serial_number: str | None = None


def url_scheme(url: str) -> str | None:
    """The ``scheme`` of ``scheme://...``, lower case, or None for a plain device path."""
    match = re.match(r"^([A-Za-z][A-Za-z0-9+.-]*)://", url)
    return match.group(1).lower() if match else None


def _by_id_links() -> dict[str, str]:
    """Real device path -> its by-id link (udev makes these only for USB adaptors)."""
    links: dict[str, str] = {}
    if _BY_ID_FOLDER.is_dir():
        for link in sorted(_BY_ID_FOLDER.iterdir()):
            try:
                links.setdefault(str(link.resolve()), str(link))
            except OSError:
                continue
    return links


def list_ports() -> list[PortInfo]:
    """The serial ports the system knows, sorted by device path.

    Pseudo-terminals (``/dev/pts/*``) and network URLs are never listed (pyserial issue #457), but
    :func:`open_port` opens them all the same.
    """
    links = _by_id_links()
    ports = []
    for port in serial_list_ports.comports():
        vid_pid = None
        if port.vid is not None and port.pid is not None:
            vid_pid = f"{port.vid:04x}:{port.pid:04x}"
        description = port.description if port.description not in (None, "n/a") else ""
        ports.append(
            PortInfo(
                device=port.device,
                description=description or "",
                by_id=links.get(str(Path(port.device).resolve())),
                vid_pid=vid_pid,
                serial_number=port.serial_number,
            )
        )
    return sorted(ports, key=lambda info: info.device)


def _existing_ports_sentence() -> str:
    try:
        devices = [info.device for info in list_ports()]
    except Exception:  # listing is a courtesy in an error message; never mask the real error
        devices = []
    if devices:
        return "Ports on this machine: " + ", ".join(devices) + "."
    return (
        "This machine lists no serial ports: check the cable and the adaptor "
        "(the kernel log, `dmesg | tail`, says whether it was seen)."
    )


def _open_error(url: str, error: BaseException) -> StationError:
    """The one sentence for a failed open of ``url``."""
    scheme = url_scheme(url)
    text = str(error)
    code = getattr(error, "errno", None)
    lowered = text.lower()
    if isinstance(error, ValueError) or "not known" in lowered or "expected a string" in lowered:
        return StationError(
            f"{url!r} is not a port URL this station understands: use a device path such as "
            "/dev/ttyUSB0, /dev/serial/by-id/..., rfc2217://HOST:PORT, socket://HOST:PORT or "
            "hwgrep://VID:PID."
        )
    if scheme in NETWORK_SCHEMES:
        if "refused" in lowered:
            return StationError(
                f"The device server at {url} refused the connection: check the host and port, "
                "and that ser2net (or the serial server) is running and its port is free."
            )
        if "waiting for option 'control'" in lowered:
            return StationError(
                f"The device server at {url} did not confirm the modem lines (DTR/RTS): add "
                "?ign_set_control to the URL, e.g. rfc2217://HOST:PORT?ign_set_control."
            )
        if "timed out" in lowered or "timeout" in lowered:
            return StationError(
                f"The device server at {url} did not answer: check the host, the port, the "
                "network cable and that ser2net (or the serial server) is running."
            )
        if (
            "name or service" in lowered
            or "not supported between" in lowered
            or ("must be" in lowered and "host" in lowered)
        ):
            return StationError(
                f"{url!r} is not a usable network port: write it as {scheme}://HOST:PORT with a "
                "host that resolves and a port number."
            )
        return StationError(
            f"Could not reach the device server at {url} ({text}): check the host, the port and "
            "that ser2net (or the serial server) is running."
        )
    if scheme == "hwgrep":
        return StationError(
            f"No serial port matches {url}: plug the adaptor in, or check the VID:PID. "
            f"{_existing_ports_sentence()}",
            remedy="list_ports",
        )
    if code == errno.ENOENT or "no such file" in lowered:
        return StationError(
            f"There is no serial port {url}: check the cable and the name. "
            + _existing_ports_sentence()
        )
    if code in (errno.EACCES, errno.EPERM) or "permission denied" in lowered:
        return StationError(
            f"Permission denied opening {url}: add your user to the dialout group "
            "(`sudo usermod -aG dialout $USER`), then log out and in again."
        )
    if code in (errno.EAGAIN, errno.EBUSY) or "exclusively lock" in lowered or "busy" in lowered:
        return StationError(
            f"{url} is busy: another program has it open (find it with `fuser -v {url}` and "
            "close it), then try again."
        )
    if "inappropriate ioctl" in lowered or code in (errno.EISDIR, errno.ENOTTY):
        return StationError(
            f"{url} is not a serial port: give the gauge's serial device. "
            + _existing_ports_sentence()
        )
    return StationError(f"Could not open {url} ({text}): check the cable and the port name.")


def own_terminal(path: str) -> bool:
    """True when ``path`` is the terminal this process talks to the operator on (its standard
    input, output or error): a pseudo-terminal number that once was a simulator's or a
    recorded gauge line and is now the operator's own window."""
    try:
        device = os.stat(path).st_rdev
    except OSError:
        return False
    if not device:
        return False
    for fd in (0, 1, 2):
        try:
            if os.isatty(fd) and os.fstat(fd).st_rdev == device:
                return True
        except OSError:
            continue
    return False


def pseudo_terminal_opened(url: str) -> float | None:
    """When the pseudo-terminal at ``url`` was opened (a POSIX time), or None when ``url`` is
    no pseudo-terminal's own path: a serial adapter, a network URL, a path that does not
    exist, or a link (a name someone chose, e.g. a bridge's ``link=``, which may point to a
    new pseudo-terminal each time its program starts, and still be that program's line).

    The kernel gives a closed pseudo-terminal's number to the next one opened: a
    ``/dev/pts/N`` opened after a session last used that path is another program's."""
    if url_scheme(url) is not None:
        return None
    try:
        status = os.lstat(url)
    except (OSError, ValueError):
        return None
    if not stat.S_ISCHR(status.st_mode):
        return None
    if os.major(status.st_rdev) not in PSEUDO_TERMINAL_MAJORS:
        return None
    # A device node's change time is its creation: reading and writing move only the others.
    return status.st_ctime


def refuse_own_terminal(url: str) -> None:
    """StationError when ``url`` is the station's own terminal. Opened as a gauge line, the
    poll request (``1\\r``) is drawn on the operator's screen (a stray "1" at the top-left) and
    the reader thread eats the operator's keys (issue 13, finding 10)."""
    if own_terminal(url):
        raise StationError(
            f"{url} is this station's own terminal, not a gauge line (a pseudo-terminal number "
            "is reused once its simulator or adapter is gone): name the gauges' port",
            field="port",
        )


def open_port(
    url: str,
    settings: SerialSettings | None = None,
    *,
    timeout: float | None = 0.1,
    exclusive: bool = True,
) -> serial.SerialBase:
    """Open ``url`` with the line ``settings``; a failure raises a one-sentence StationError.

    ``exclusive`` takes a POSIX ``flock`` on local devices so a second program cannot steal frames;
    network URLs have no local lock, so it is not passed to them.
    """
    if not isinstance(url, str) or not url.strip():
        raise StationError(
            "No port given: name the gauge's port, e.g. /dev/ttyUSB0 or rfc2217://HOST:PORT",
            remedy="list_ports",
            field="port",
        )
    url = url.strip()
    settings = settings or SerialSettings()
    kwargs: dict[str, object] = dict(settings.as_kwargs(), timeout=timeout)
    if exclusive and url_scheme(url) in (None, "hwgrep"):
        kwargs["exclusive"] = True
    if url_scheme(url) is None:
        refuse_own_terminal(url)
    try:
        return serial.serial_for_url(url, **kwargs)
    except termios.error as error:
        # Some kernels refuse 7 data bits or parity on a pseudo-terminal (EINVAL); a real
        # UART takes them.
        raise StationError(
            f"{url} refused the line settings {settings.describe()} ({error.args[-1]}); a "
            "pseudo-terminal may only take 8N1",
            remedy="serial_settings",
        ) from error
    except (serial.SerialException, OSError, ValueError, TypeError) as error:
        raise _open_error(url, error) from error
