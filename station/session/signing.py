"""Signing a session's ``finish`` with the station's own Ed25519 key.

The hash chain finds any edit of a line, but someone who rewrites every later line (or appends,
or cuts) and recomputes the hashes makes a chain that is intact again. A signature closes that
for finished sessions: the ``finish`` event carries an Ed25519 signature over the session id,
the ``prev`` hash (which covers every line before it) and its ``seq``, made with a key that only
this station holds. The header names the key (``signer``: its id and public key), so
``station verify`` checks the signature and prints the key id; a rechained or extended forgery
cannot be re-signed without the private key. A forger who re-signs with a key of their own puts
that key in the header: ``station verify`` accepts only keys in the trust store
(:mod:`station.session.trust`). A forger who strips ``signer`` and the signature makes a file
that looks older than signing: :func:`predates_signing` tells the two apart by the header's date.

The key is made on first use in ``$XDG_CONFIG_HOME/station/signing-key.pem`` (else
``~/.config/station/``), PKCS#8, mode 0600, in a folder of mode 0700, never through a link;
its public half goes into the trust store when the key is made or first used.
"""

from __future__ import annotations

import base64
import contextlib
import hashlib
import os
import stat
import tempfile
from collections.abc import Mapping
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path
from typing import Any, Literal, overload

from cryptography.exceptions import InvalidSignature
from cryptography.hazmat.primitives import serialization
from cryptography.hazmat.primitives.asymmetric.ed25519 import Ed25519PrivateKey, Ed25519PublicKey

from station.errors import StationError
from station.session.durable import refuse_links_below

KEY_FILE_NAME = "signing-key.pem"
SIGNATURE_CONTEXT = b"station-finish/1"
KEY_ALGORITHM = "ed25519"

SIGNING_SINCE = datetime(2026, 11, 29, tzinfo=UTC)
"""The day the first version that signs its sessions was made. Every session that version and
later ones write names its ``signer`` in the header and signs its finish; a header without
``signer`` is genuine only when it is dated before this (:func:`predates_signing`)."""


def config_folder() -> Path:
    """``$XDG_CONFIG_HOME/station`` (``~/.config/station`` when the variable is unset);
    StationError when it is a symbolic link."""
    base = Path(os.environ.get("XDG_CONFIG_HOME") or str(Path.home() / ".config"))
    return refuse_links_below(base, base / "station", "the station's settings and signing key")


def predates_signing(header: Mapping[str, Any]) -> bool:
    """Whether a header without ``signer`` may be genuine: its ``created`` is a date before
    :data:`SIGNING_SINCE`, when no station signed yet. A header dated since then, or without a
    readable date, was written by a signing version, so its missing ``signer`` was removed.

    The date is the file's own word: a forger who also backdates the header passes this rule,
    which is why ``station verify`` says of every unsigned session that nothing shows who wrote
    it, and only an anchor on a filed report vouches for it."""
    created = header.get("created")
    if not isinstance(created, str):
        return False
    try:
        moment = datetime.fromisoformat(created)
    except ValueError:
        return False
    return moment.tzinfo is not None and moment < SIGNING_SINCE


def key_id(public_key: bytes) -> str:
    """A key's short name: the first 16 hex digits of the sha256 of its 32 raw bytes."""
    return hashlib.sha256(public_key).hexdigest()[:16]


@dataclass(frozen=True)
class StationKey:
    """The station's signing key, loaded."""

    private: Any  # cryptography's Ed25519PrivateKey
    public_key: bytes
    """The raw 32-byte public key."""

    @property
    def id(self) -> str:
        """The key id printed by ``station verify``."""
        return key_id(self.public_key)

    def header_field(self) -> dict[str, str]:
        """What goes into a session header's ``signer``."""
        return {
            "key": self.id,
            "algorithm": "ed25519",
            "public_key": base64.b64encode(self.public_key).decode("ascii"),
        }

    def sign(self, message: bytes) -> str:
        """The base64 Ed25519 signature of ``message``."""
        return base64.b64encode(self.private.sign(message)).decode("ascii")


def finish_message(session_id: str, prev: str, seq: int) -> bytes:
    """The bytes a finish event's signature covers: context, session id, ``prev``, ``seq``."""
    return b"\0".join(
        (SIGNATURE_CONTEXT, session_id.encode("utf-8"), prev.encode("ascii"), str(seq).encode())
    )


@overload
def station_key(create: Literal[True] = True) -> StationKey: ...
@overload
def station_key(create: bool) -> StationKey | None: ...
def station_key(create: bool = True) -> StationKey | None:
    """The station's key, made on first use when ``create`` (None when it does not exist and
    ``create`` is False). StationError when the key file cannot be read or made."""
    path = config_folder() / KEY_FILE_NAME
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK)
    except FileNotFoundError:
        if not create:
            return None
        return _make_key(path)
    except OSError as error:
        raise StationError(
            f"cannot read the station's signing key {path}: {error.strerror}"
        ) from None
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode) or info.st_size > 4096:
            raise StationError(f"the station's signing key {path} is not a key file; move it away")
        data = os.read(fd, 4096)
    finally:
        os.close(fd)
    try:
        private = serialization.load_pem_private_key(data, password=None)
    except (ValueError, TypeError):
        raise StationError(
            f"the station's signing key {path} is damaged; move it away (a new key is made)"
        ) from None
    if not isinstance(private, Ed25519PrivateKey):
        raise StationError(f"the station's signing key {path} is not an Ed25519 key")
    key = StationKey(private, _raw_public(private))
    if create:
        _trust_own_key(key)
    return key


def station_public_key() -> bytes | None:
    """This station's raw public key, when its private key can be read; None when it is
    missing, damaged, a link or of another type (``station verify`` then goes by the trust
    store alone)."""
    try:
        key = station_key(create=False)
    except StationError:
        return None
    return key.public_key if key is not None else None


def _trust_own_key(key: StationKey) -> None:
    """Put this station's public key in the trust store (a key made before the store existed
    is put there on its first use), so ``station verify`` needs no private key."""
    # Imported here: the trust store builds on this module's key ids.
    from station.session.trust import trust_own_key

    trust_own_key(key.public_key)


def _make_key(path: Path) -> StationKey:
    """Make the key and put it in place whole: written to a file of its own, then linked to
    ``path`` (which fails if another session made one first: that one is used). A reader never
    sees a half-written key."""
    private = Ed25519PrivateKey.generate()
    pem = private.private_bytes(
        serialization.Encoding.PEM,
        serialization.PrivateFormat.PKCS8,
        serialization.NoEncryption(),
    )
    try:
        path.parent.mkdir(mode=0o700, parents=True, exist_ok=True)
        fd, draft = tempfile.mkstemp(prefix=".signing-key-", dir=path.parent)
    except OSError as error:
        raise StationError(
            f"cannot make the station's signing key in {path.parent}: {error.strerror}"
        ) from None
    try:
        os.fchmod(fd, 0o600)
        os.write(fd, pem)
        os.fsync(fd)
        os.close(fd)
        fd = -1
        os.link(draft, path)
        key = StationKey(private, _raw_public(private))
    except FileExistsError:
        # Another session made it first: use that one.
        theirs = station_key(create=False)
        assert theirs is not None
        return theirs
    except OSError as error:
        raise StationError(
            f"cannot write the station's signing key {path}: {error.strerror}"
        ) from None
    finally:
        if fd >= 0:
            os.close(fd)
        with contextlib.suppress(OSError):
            os.unlink(draft)
    _trust_own_key(key)
    return key


def _raw_public(private: Any) -> bytes:
    return private.public_key().public_bytes(
        serialization.Encoding.Raw, serialization.PublicFormat.Raw
    )


@dataclass(frozen=True)
class SignatureCheck:
    """What ``station verify`` says about a finish signature."""

    ok: bool
    key: str
    """The key id the header names ('' for a session made before signing)."""
    message: str


def check_finish_signature(header: Mapping[str, Any], finish: Mapping[str, Any]) -> SignatureCheck:
    """Check ``finish`` (a finish event as stored, with its ``prev`` and ``seq``) against the
    header's ``signer``. A header without ``signer`` is not ok here: whether an unsigned session
    may be genuine is :func:`predates_signing`'s question, asked before this one."""
    signer = header.get("signer")
    if signer is None:
        return SignatureCheck(False, "", "the session is unsigned")
    try:
        public = base64.b64decode(str(signer["public_key"]), validate=True)
        named = str(signer["key"])
        public_key = Ed25519PublicKey.from_public_bytes(public)
    except (KeyError, TypeError, ValueError):
        return SignatureCheck(False, "", "the header's signer is not an Ed25519 public key")
    if key_id(public) != named:
        return SignatureCheck(False, named, "the header's key id does not match its public key")
    signature = finish.get("signature")
    if not isinstance(signature, str):
        return SignatureCheck(False, named, "the finish event is not signed")
    try:
        public_key.verify(
            base64.b64decode(signature, validate=True),
            finish_message(str(header.get("session")), str(finish.get("prev")), finish["seq"]),
        )
    except (InvalidSignature, ValueError):
        return SignatureCheck(
            False,
            named,
            "the finish event's signature does not match (the file was rewritten without the "
            "station's key)",
        )
    return SignatureCheck(True, named, f"finish signed by station key {named}")
