"""``station simulate`` as a real subprocess: URL first, the seeded model's values, clean exit."""

from __future__ import annotations

import signal
import subprocess

import pytest
from helpers import STATION, start_simulator, stop_simulator

from station.instruments.protocols import get_protocol
from station.instruments.simulator import AxisModel, FixtureModel, GaugeSpec
from station.instruments.transport import open_port


def finish(process: subprocess.Popen, sig: int) -> tuple[int, str]:
    err = stop_simulator(process, sig)
    return process.returncode, err


def poll(url: str, name: str, times: int) -> list[bytes]:
    protocol = get_protocol(name)
    port = open_port(url, protocol.settings, timeout=2.0)
    try:
        frames = []
        for _ in range(times):
            port.write(protocol.request("1"))
            frames.append(port.read_until(protocol.terminator).strip())
        return frames
    finally:
        port.close()


@pytest.mark.parametrize(("where", "sig"), [("--pty", signal.SIGTERM), ("--tcp", signal.SIGINT)])
def test_url_first_then_the_seeded_values_then_a_clean_exit(where: str, sig: int) -> None:
    args = [
        "--protocol",
        "idh",
        "--channels",
        "x",
        "--seed",
        "42",
        "--bias",
        "x=0.25",
        "--noise",
        "0.01",
        "--skew",
        "3",
        "--resolution",
        "0.0005",
        where,
    ]
    if where == "--tcp":
        args.append("0")
    process, url = start_simulator(*args)
    try:
        if where == "--pty":
            assert url.startswith("/dev/pts/")
        else:
            assert url.startswith("socket://127.0.0.1:") and not url.endswith(":0")
        frames = poll(url, "idh", 4)
    finally:
        code, err = finish(process, sig)
    model = FixtureModel(
        {"x": AxisModel(bias=0.25, noise=0.01, skew=3.0)}, GaugeSpec(resolution=0.0005)
    )
    protocol = get_protocol("idh")
    values = [protocol.parse(frame).value for frame in frames]
    assert values == pytest.approx([model.value("x", k, 42) for k in range(4)], abs=1e-9)
    assert code == 0
    assert "Traceback" not in err


def test_error_rate_one_sends_only_error_frames() -> None:
    process, url = start_simulator("--protocol", "mitutoyo", "--error-rate", "1", "--channels", "x")
    try:
        frames = poll(url, "mitutoyo", 2)
    finally:
        code, _ = finish(process, signal.SIGTERM)
    assert frames == [b"911", b"911"]
    assert code == 0


@pytest.mark.parametrize(
    ("args", "sentence"),
    [
        (["--protocol", "nope"], "unknown gauge protocol 'nope'"),
        (["--protocol", "sylvac"], "carries one gauge per port"),
        (["--protocol", "mitutoyo", "--bias", "q=1"], "--bias names channel 'q'"),
        (
            ["--protocol", "mitutoyo", "--error-rate", "2"],
            "--error-rate must be from 0 to 1, not 2",
        ),
        (
            ["--protocol", "mitutoyo", "--resolution", "-1"],
            "--resolution must be from 1e-06 to 1, not -1",
        ),
    ],
)
def test_bad_options_exit_2_with_a_sentence(args: list[str], sentence: str) -> None:
    result = subprocess.run(
        [*STATION, "simulate", *args], capture_output=True, text=True, timeout=30
    )
    assert result.returncode == 2
    assert sentence in result.stderr
    assert result.stdout == ""
    assert "Traceback" not in result.stderr


def test_link_refuses_to_replace_a_file(tmp_path) -> None:
    """Review finding 10: --link PATH used to overwrite PATH, and unlink it on exit."""
    precious = tmp_path / "notes.txt"
    precious.write_text("keep me")
    result = subprocess.run(
        [*STATION, "simulate", "--protocol", "mitutoyo", "--link", str(precious)],
        capture_output=True,
        text=True,
        timeout=30,
    )
    assert result.returncode == 2
    assert result.stderr.startswith(f"station: {precious} exists and is not a simulator's link")
    assert precious.read_text() == "keep me"


def test_link_replaces_a_stale_simulator_link(tmp_path) -> None:
    link = tmp_path / "gauge"
    link.symlink_to("/dev/pts/999999")  # what a killed simulator leaves behind
    process, url = start_simulator("--protocol", "mitutoyo", "--link", str(link))
    assert url == str(link) and link.resolve() != "/dev/pts/999999"
    assert len(poll(url, "mitutoyo", 1)) == 1
    code, err = finish(process, signal.SIGTERM)
    assert code == 0, err
    assert not link.is_symlink()


@pytest.mark.parametrize("sig", [signal.SIGHUP, signal.SIGINT, signal.SIGTERM])
def test_a_hang_up_cleans_up_like_sigterm(sig: int) -> None:
    """Review finding 10: after SIGHUP (an SSH session closing) the /tmp/station-sim-* folder
    of the disconnect link was left behind."""
    from pathlib import Path

    process, url = start_simulator("--protocol", "mitutoyo", "--disconnect-every", "30")
    folder = Path(url).parent
    assert folder.name.startswith("station-sim-") and folder.is_dir()
    code, err = finish(process, sig)
    assert code == 0, err
    assert not folder.exists()
