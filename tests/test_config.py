"""The strict config reader: missing, unknown and out-of-range keys are named."""

from __future__ import annotations

import pytest

from motioncue import ConfigError
from motioncue._config import ConfigReader, find_config
from motioncue.output._transport import parse_target


def test_unknown_key_is_named() -> None:
    r = ConfigReader({"stroke_mm": 100.0, "strok_mm": 3}, "x.toml")
    assert r.number("stroke_mm") == 100.0
    with pytest.raises(ConfigError, match="strok_mm"):
        r.finish()


def test_missing_key_is_named() -> None:
    r = ConfigReader({}, "x.toml")
    with pytest.raises(ConfigError, match="missing key 'lead_mm'"):
        r.number("lead_mm")


def test_out_of_range_names_key_value_and_range() -> None:
    r = ConfigReader({"lead_mm": -5}, "x.toml")
    with pytest.raises(ConfigError, match=r"lead_mm = -5.0 .*\(0.0, inf\]"):
        r.number("lead_mm", lo=0.0, lo_open=True)


def test_types_are_checked() -> None:
    r = ConfigReader({"n": 1.5, "b": 1, "v": [1, 2]}, "x.toml")
    with pytest.raises(ConfigError, match="an integer"):
        r.integer("n")
    with pytest.raises(ConfigError, match="true or false"):
        r.boolean("b")
    with pytest.raises(ConfigError, match="3 finite numbers"):
        r.vector("v", 3)


def test_defaults_do_not_count_as_unknown() -> None:
    r = ConfigReader({"a": 1}, "x.toml")
    assert r.integer("a") == 1
    assert r.number("b", 2.5) == 2.5
    r.finish()


def test_unknown_bundled_config() -> None:
    with pytest.raises(ConfigError, match="unknown platforms config 'nope'"):
        find_config("platforms", "nope")


@pytest.mark.parametrize(
    ("url", "scheme", "host", "port", "path"),
    [
        ("udp://127.0.0.1:7408", "udp", "127.0.0.1", 7408, ""),
        ("serial:///dev/ttyUSB0?baud=19200", "serial", "", 0, "/dev/ttyUSB0"),
        ("pcap:out/ride.pcap", "pcap", "", 0, "out/ride.pcap"),
        ("file:ride.bin", "file", "", 0, "ride.bin"),
    ],
)
def test_target_urls(url: str, scheme: str, host: str, port: int, path: str) -> None:
    t = parse_target(url)
    assert (t.scheme, t.host, t.port, t.path) == (scheme, host, port, path)


def test_serial_options() -> None:
    assert parse_target("serial:///dev/ttyUSB0?baud=9600").options == {"baud": "9600"}


@pytest.mark.parametrize("url", ["127.0.0.1:7408", "tcp://a:1", "udp://host", "file:", "nothing"])
def test_bad_targets(url: str) -> None:
    with pytest.raises(ConfigError):
        parse_target(url)
