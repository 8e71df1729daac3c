"""``station keys``: this station's public key and the trust store of station keys."""

from __future__ import annotations

import argparse

DESCRIPTION = """\
The station keys `station verify` trusts. A finished session is signed with
this station's key; verify accepts a session only when the key that signed it
is in the trust store: this station's own key and the keys added here (the
plant's other stations), in $XDG_CONFIG_HOME/station/trusted-keys
(~/.config/station/trusted-keys).

  station keys show                  print this station's public key (made on
                                     first use): save it as FILE.pub on the
                                     stations that should trust this one
  station keys trust FILE.pub        trust the key in FILE.pub (what `keys
    [--name NAME]                    show` printed on the other station)
  station keys list                  the trusted keys: id and name

exit codes: 0 done; 2 bad input (a file that is not a key, a damaged store)
"""


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    """Register ``station keys`` and its actions."""
    parser = subparsers.add_parser(
        "keys",
        help="this station's public key and the station keys verify trusts",
        description=DESCRIPTION,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    actions = parser.add_subparsers(dest="keys_command", metavar="ACTION", required=True)
    show = actions.add_parser("show", help="print this station's public key, for others to trust")
    show.set_defaults(func=run_show)
    trust = actions.add_parser("trust", help="trust the station key in FILE.pub")
    trust.add_argument("file", metavar="FILE.pub", help="what `station keys show` printed there")
    trust.add_argument("--name", help="the name to trust it under (else the name in the file)")
    trust.set_defaults(func=run_trust)
    listing = actions.add_parser("list", help="the trusted station keys")
    listing.set_defaults(func=run_list)


def run_show(args: argparse.Namespace) -> int:
    """Print this station's public key line (the key is made when there is none yet)."""
    from station.session.signing import station_key
    from station.session.trust import PublicKey, own_key_name

    key = station_key()
    assert key is not None  # made on first use
    name = own_key_name().removeprefix("this station, ")
    print(PublicKey(key.public_key, name).line)
    return 0


def run_trust(args: argparse.Namespace) -> int:
    """Add the key in ``args.file`` to the trust store."""
    from dataclasses import replace

    from station.session.trust import key_name, read_public_key_file, trust_key, trust_store_path

    key = read_public_key_file(args.file)
    if args.name is not None:
        key = replace(key, name=key_name(args.name))
    already = trust_key(key)
    if already is not None:
        print(f"station key {key.id} is already trusted as {already.name or '(no name)'}")
    else:
        print(f"trusted station key {key.id} as {key.name or '(no name)'} in {trust_store_path()}")
    return 0


def run_list(args: argparse.Namespace) -> int:
    """Print the trust store: one key a line, id then name."""
    from station.session.signing import station_public_key
    from station.session.trust import trust_store_path, trusted_keys

    keys = trusted_keys()
    own = station_public_key()
    print(f"trust store: {trust_store_path()}")
    if own is not None and all(key.raw != own for key in keys):
        # A key made before the store existed, not yet used since: verify trusts it too.
        from station.session.trust import PublicKey, own_key_name

        keys.insert(0, PublicKey(own, own_key_name()))
    if not keys:
        print("no keys trusted yet: this station's own is added when it records its first session")
    for key in keys:
        print(f"{key.id}  {key.name or '(no name)'}")
    return 0
