"""The trust store: the station keys whose signatures ``station verify`` accepts.

As SSH keeps the host keys it knows, a station keeps the public keys of the stations it trusts
in ``$XDG_CONFIG_HOME/station/trusted-keys`` (else ``~/.config/station/``), one a line::

    ed25519 <base64 of the 32-byte public key> <name>

the line ``station keys show`` prints. Its own key is put there when the key is made or first
used; a user adds the plant's other stations with ``station keys trust``. A key that is later
replaced stays in the store, so the sessions it signed still verify. Lines starting with ``#``
and blank lines are ignored. ``station verify`` needs only these public keys: a damaged, empty,
linked or foreign private key does not stop it.
"""

from __future__ import annotations

import base64
import binascii
import contextlib
import socket
from dataclasses import dataclass
from pathlib import Path

from cryptography.hazmat.primitives.asymmetric.ed25519 import Ed25519PublicKey

from station.errors import StationError
from station.inputfiles import read_input_bytes
from station.plain import has_unsafe_characters, plain
from station.session.durable import write_text_durably
from station.session.signing import KEY_ALGORITHM, config_folder, key_id, station_public_key

TRUST_FILE_NAME = "trusted-keys"
_MAX_STORE_BYTES = 1 << 20
_MAX_NAME_LENGTH = 200
_KEY_LINE_HELP = "a line 'ed25519 KEY NAME', as `station keys show` prints it"


@dataclass(frozen=True)
class PublicKey:
    """A station's public key and the name it is trusted under."""

    raw: bytes
    """The raw 32-byte Ed25519 public key."""
    name: str

    @property
    def id(self) -> str:
        """The key id ``station verify`` prints."""
        return key_id(self.raw)

    @property
    def line(self) -> str:
        """The key as one line of the trust store (what ``station keys show`` prints)."""
        encoded = base64.b64encode(self.raw).decode("ascii")
        return f"{KEY_ALGORITHM} {encoded} {self.name}".rstrip()


def trust_store_path() -> Path:
    """The trust store file: ``trusted-keys`` in the station's config folder."""
    return config_folder() / TRUST_FILE_NAME


def key_name(text: str) -> str:
    """``text`` as a key's name: one line, spaces collapsed. StationError when it holds a
    control character or is longer than 200 characters."""
    name = " ".join(text.split())
    if has_unsafe_characters(name) or len(name) > _MAX_NAME_LENGTH:
        raise StationError(
            f"the key name {plain(name, limit=60)!r} is not one line of plain text of at most "
            f"{_MAX_NAME_LENGTH} characters; give another with --name"
        )
    return name


def parse_public_key(line: str, where: str) -> PublicKey:
    """A key from one line ``ed25519 BASE64 NAME``; StationError naming ``where`` (the file
    and line) when it is not one."""
    words = line.strip().split(maxsplit=2)
    try:
        if len(words) < 2 or words[0] != KEY_ALGORITHM:
            raise ValueError
        raw = base64.b64decode(words[1], validate=True)
        Ed25519PublicKey.from_public_bytes(raw)
    except (ValueError, binascii.Error):
        raise StationError(
            f"{plain(where, limit=300)} is not a station public key: give {_KEY_LINE_HELP}"
        ) from None
    return PublicKey(raw, key_name(words[2]) if len(words) == 3 else "")


def _key_lines(text: str) -> list[tuple[int, str]]:
    return [
        (number, line)
        for number, line in enumerate(text.splitlines(), start=1)
        if line.strip() and not line.lstrip().startswith("#")
    ]


def _read_text(path: Path, what: str) -> str:
    data = read_input_bytes(path, what, _MAX_STORE_BYTES)
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        raise StationError(
            f"{plain(str(path), limit=300)} is not UTF-8 text: give {_KEY_LINE_HELP}"
        ) from None


def read_public_key_file(path: str | Path) -> PublicKey:
    """The one key in ``path`` (a file holding what ``station keys show`` printed on another
    station). StationError when it holds none, more than one, or something else."""
    path = Path(path)
    lines = _key_lines(_read_text(path, "public key file"))
    if len(lines) != 1:
        raise StationError(
            f"{plain(str(path), limit=300)} holds {len(lines)} keys, not one: give {_KEY_LINE_HELP}"
        )
    number, line = lines[0]
    return parse_public_key(line, f"{path} line {number}")


def trusted_keys() -> list[PublicKey]:
    """The keys in the trust store, in its order (none when it does not exist yet).
    StationError naming the line when a line is not a key: verify cannot judge without it."""
    path = trust_store_path()
    if not path.exists() and not path.is_symlink():
        return []
    text = _read_text(path, "trust store")
    return [
        parse_public_key(line, f"the trust store {path} line {number}")
        for number, line in _key_lines(text)
    ]


def find_trusted(raw: bytes) -> PublicKey | None:
    """The trusted key with these raw bytes: from the store, else this station's own key when
    its private key can be read (a key made before the store existed); None when untrusted."""
    for key in trusted_keys():
        if key.raw == raw:
            return key
    if station_public_key() == raw:
        return PublicKey(raw, own_key_name())
    return None


def own_key_name() -> str:
    """The name this station's own key is trusted under: ``this station, <host name>``."""
    return key_name(plain(f"this station, {socket.gethostname()}", limit=_MAX_NAME_LENGTH))


def trust_key(key: PublicKey) -> PublicKey | None:
    """Add ``key`` to the trust store (written whole, mode 0600). Returns the entry already
    there when the key is trusted (under that entry's name), None when it was added."""
    path = trust_store_path()
    existing = trusted_keys()
    for entry in existing:
        if entry.raw == key.raw:
            return entry
    text = _read_text(path, "trust store") if existing or path.exists() else ""
    if text and not text.endswith("\n"):
        text += "\n"
    if not text:
        text = "# station keys whose signed sessions `station verify` accepts (station keys)\n"
    try:
        path.parent.mkdir(mode=0o700, parents=True, exist_ok=True)
        write_text_durably(path, text + key.line + "\n", mode=0o600)
    except OSError as error:
        raise StationError(f"cannot write the trust store {path}: {error.strerror}") from None
    return None


def trust_own_key(raw: bytes) -> None:
    """Put this station's own public key in the trust store, when it is not there yet. Best
    effort: a store that cannot be read or written never stops a session from being signed
    (verify then reads the key from the private key, as before the store existed)."""
    with contextlib.suppress(StationError, OSError):
        trust_key(PublicKey(raw, own_key_name()))
