"""Split the byte stream of a serial line into frames on the protocol's terminator.

A reader feeds whatever ``read()`` returned; the splitter returns every complete frame (the
terminator removed) and keeps the unfinished rest for the next feed. It never uses
``readline()`` (which only ends on LF, while most gauges end frames with CR).

Rules, the same for every protocol:

* **Line terminators** (any terminator made only of CR and LF: ``\\r``, ``\\n``, ``\\r\\n``)
  end a frame at *any* CR or LF. Real lines mix them: a CRLF device on a CR protocol, a lone
  CR from a CRLF device, a stray LF left over before the next CR-terminated frame, a CRLF torn
  between two reads. Splitting on either byte and dropping blank frames handles all of these
  the same way, and a device's CRLF never leaves an LF glued to the front of the next frame.
* **Other terminators** (e.g. ``;`` or ``\\x03``, configurable for ASCII adaptors) end a frame
  only at the exact byte sequence, also when it is torn between two reads.
* Each frame is stripped of surrounding spaces, tabs, CR, LF and NUL (line noise, idle-line
  NULs after a power-up, padding). A frame that is empty after stripping is not a frame. So a
  Sylvac's space sign is dropped; the protocol reads an unsigned value as positive.
* The buffer is bounded: when more than ``max_frame`` bytes arrive without a terminator, the
  run is discarded and reported once as an :class:`Overflow` (the reader counts it as a
  ``malformed`` rejection); everything up to the next terminator is dropped too, and framing
  resumes after it.
"""

from __future__ import annotations

from dataclasses import dataclass

NOISE = b" \t\r\n\x00"
"""Bytes stripped from both ends of every frame."""

_LINE_BYTES = frozenset(b"\r\n")


@dataclass(frozen=True)
class Overflow:
    """A run of more than ``max_frame`` bytes without a terminator, discarded by the splitter."""

    head: bytes
    """The first ``max_frame`` bytes of the run, kept so the operator can see what came."""

    @property
    def detail(self) -> str:
        """A sentence for the rejection log."""
        return (
            f"more than {len(self.head)} bytes without a frame terminator were discarded; "
            "check the protocol, the terminator and the serial settings"
        )


class FrameSplitter:
    """Cut a byte stream into frames on ``terminator`` with a bounded buffer.

    ``feed(data)`` returns the frames completed by ``data`` (bytes, stripped, terminator
    removed) and an :class:`Overflow` for each over-long run, in stream order. ``reset()``
    drops a partial frame: on reconnect, and before a poll so that stale half-frames are
    never completed by the answer.
    """

    def __init__(self, terminator: bytes, max_frame: int = 256) -> None:
        if not terminator:
            raise ValueError("a frame terminator must be at least one byte")
        if max_frame < 1:
            raise ValueError("max_frame must be at least 1")
        self.terminator = bytes(terminator)
        self.max_frame = max_frame
        self._line_mode = set(self.terminator) <= _LINE_BYTES
        # Bytes at the end of the buffer that may be the start of a torn multi-byte terminator:
        # they neither count towards max_frame nor get dropped while discarding.
        self._slack = 0 if self._line_mode else len(self.terminator) - 1
        self._buffer = b""
        # True after an overflow, until the next terminator: the rest of the run is dropped.
        self._discarding = False

    def reset(self) -> None:
        """Forget any partial frame (and an overflow in progress)."""
        self._buffer = b""
        self._discarding = False

    @property
    def pending(self) -> int:
        """Bytes held for an unfinished frame."""
        return len(self._buffer)

    def feed(self, data: bytes) -> list[bytes | Overflow]:
        """Add bytes from the line; return the frames (and overflows) they complete."""
        buffer = self._buffer + data if self._buffer else bytes(data)
        if not buffer:
            return []
        if self._line_mode:
            parts = buffer.splitlines()
            # splitlines() drops the final terminator, so look at the last byte to tell a
            # finished last line from an unfinished one.
            tail = b"" if buffer[-1] in _LINE_BYTES else parts.pop()
        else:
            parts = buffer.split(self.terminator)
            tail = parts.pop()
        out: list[bytes | Overflow] = []
        max_frame = self.max_frame
        if parts and self._discarding:
            # The first part is the end of a run already reported as an overflow.
            parts = parts[1:]
            self._discarding = False
        for part in parts:
            if len(part) > max_frame:
                # A terminated run can also be over-long when it arrives in one read.
                out.append(Overflow(part[:max_frame]))
                continue
            frame = part.strip(NOISE)
            if frame:
                out.append(frame)
        if not self._discarding and len(tail) > max_frame + self._slack:
            out.append(Overflow(tail[:max_frame]))
            self._discarding = True
        if self._discarding:
            # Inside a reported run: keep only what could start a torn terminator.
            tail = tail[len(tail) - self._slack :] if self._slack else b""
        self._buffer = tail
        return out
