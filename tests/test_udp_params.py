"""The IMAX and MBOX parameter tables are data (``params.toml``) read by one loader."""

from __future__ import annotations

import sys

import pytest

from motioncue import ConfigError
from motioncue.output._udp_common import ParameterTable
from motioncue.output.imax import PA_SPEC, pa_address, pa_name
from motioncue.output.mbox import FN_SPEC, fn_address, fn_name

_NAMES = """[names]
pattern = '^q[ _]?([0-9a-f]{1,2})$'
canonical = "Q{:02X}"
what = "a Q name"

[parameters]
"""


def _table(tmp_path, monkeypatch, rows: str) -> ParameterTable:
    pkg = tmp_path / "toy_params_pkg"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    (pkg / "params.toml").write_text(_NAMES + rows)
    monkeypatch.syspath_prepend(str(tmp_path))
    sys.modules.pop("toy_params_pkg", None)
    return ParameterTable.load("toy_params_pkg")


def test_a_table_is_read_in_file_order_with_its_names(tmp_path, monkeypatch):
    t = _table(tmp_path, monkeypatch, 'Q1F = [0, 9, 3, "b"]\nQ02 = [-1, 1, 0, "a"]\n')
    assert list(t.spec) == ["Q1F", "Q02"] and t.spec["Q02"] == (-1, 1, 0, "a")
    assert t.by_address == {0x1F: "Q1F", 0x02: "Q02"} and t.names.name("q 1f") == "Q1F"


@pytest.mark.parametrize(
    "row",
    [
        'Q01 = [0, 9, 10, "default above hi"]',
        "Q01 = [0, 9, 1]",
        'Q01 = [0, 9.0, 1, "float"]',
        'Q01 = [0, true, 1, "bool"]',
        "Q01 = [0, 9, 1, 5]",
        'q01 = [0, 9, 1, "not canonical"]',
    ],
)
def test_a_malformed_row_is_refused_naming_it(tmp_path, monkeypatch, row):
    with pytest.raises(ConfigError, match=r"toy_params_pkg/params\.toml: [Qq]01 = "):
        _table(tmp_path, monkeypatch, row + "\n")


def test_the_packaged_tables_keep_their_rows():
    # spot rows against the manuals (IMAX 2.3.1, SC-MBOX chapter 5) and the examples
    assert len(PA_SPEC) == 124 and len(FN_SPEC) == 87
    assert PA_SPEC["PA41"] == (1, 65535, 50, "actuator screw lead, 0.1 mm (ex 5.5: 50)")
    assert PA_SPEC["PA3a"][3] == "axis 11 homing torque (5.4: 35..47)"
    assert FN_SPEC["Fn08C"] == (-32, 1, -1, "DO12 source")
    assert pa_name("pa a0") == "PAa0" and pa_address("PAA0") == 0xA0
    assert fn_name("fn_0c1") == "Fn0C1" and fn_address("Fn090") == 0x90
    for name in (*PA_SPEC, *FN_SPEC):
        lo, hi, default, _ = {**PA_SPEC, **FN_SPEC}[name]
        assert lo <= default <= hi
