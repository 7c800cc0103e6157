"""Numbers in an edited golden file (issue 31): each is refused, exit 2, located at the file's line and
column and naming the field, before any comparison.

Found by an outside probe of 24 edited golden files: `every 0`, `dt 0`, huge times and bad header numbers
ended `scenario check` with exit 70 (ZeroDivisionError, OverflowError, "range() arg 3 must not be zero"); a
tolerance `atol=nan` made `check` report "matches" for a 5.7 m difference (|a - b| <= nan is false, so no
sample was ever over it); deeply nested JSON in a `var` line was a RecursionError.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from runner.ci.golden import BaselineError, dumps
from runner.ci.golden_read import MAX_SAMPLES, loads

from .test_golden_format import recording

#: (the start of the line edited, its new text, the field the message names, the token it points at)
EDITS = [
    ("every ", "every 0", "`every`", "0"),
    ("every ", "every -2", "`every`", "-2"),
    ("every ", "every 2.5", "`every`", "2.5"),
    ("every ", "every 1e30", "`every`", "1e30"),
    ("dt ", "dt 0", "`dt`", "0"),
    ("dt ", "dt -0.1", "`dt`", "-0.1"),
    ("dt ", "dt nan", "`dt`", "nan"),
    ("dt ", "dt inf", "`dt`", "inf"),
    ("dt ", "dt ten", "`dt`", "ten"),
    ("steps ", "steps 1e999", "`steps`", "1e999"),
    ("steps ", "steps -1", "`steps`", "-1"),
    ("steps ", "steps 100000000000000000000", "`steps`", "100000000000000000000"),
    ("format ", "format \N{SUPERSCRIPT ONE}", "`format`", "\N{SUPERSCRIPT ONE}"),
    ("format ", "format 1e3", "`format`", "1e3"),
    ("end_time ", "end_time nan", "`end_time`", "nan"),
    ("tolerance ", "tolerance default atol=nan rtol=1e-06", "`tolerance default atol`", "atol=nan"),
    ("tolerance ", "tolerance default atol=1e-06 rtol=-1", "`tolerance default rtol`", "rtol=-1"),
    ("tolerance ", "tolerance default atol=inf", "`tolerance default atol`", "atol=inf"),
    ("tolerance ", "tolerance pos atol=abc", "`tolerance pos atol`", "atol=abc"),
    ("event 0.4", "event nan space input", "event time", "nan"),
    ("sound ", "sound -1 thud start", "sound time", "-1"),
    ("verdict ", 'verdict pass inf "box falls far enough" 0.46045 "0.46 ± 0.01"', "verdict time", "inf"),
    ("body 0.2 box", "body 1e300 box pos 0 0 1.7057 quat 1 0 0 0 vel 0 0 -1.962 angvel 0 0 0", "body time", "1e300"),
    ("body 0.2 box", "body inf box pos 0 0 1.7057 quat 1 0 0 0 vel 0 0 -1.962 angvel 0 0 0", "body time", "inf"),
    ("body 0.2 box", "body 0.2 box pos 0 0 1e400 quat 1 0 0 0 vel 0 0 -1.962 angvel 0 0 0", "body `box` pos.z",
     "1e400"),
    ("body 0.2 box", "body 0.2 box pos 0 0 nan quat 1 0 0 0 vel 0 0 -1.962 angvel 0 0 0", "body `box` pos.z", "nan"),
    ("joint 0.2", "joint 0.2 slider position 0.02 velocity -inf motor_force nan", "joint `slider` velocity", "-inf"),
    ("joint 0.2", "joint 0.2 slider position x velocity 0.1 motor_force nan", "joint `slider` position", "x"),
    ("body 0.2 box", "body 0.3 box pos 0 0 1.7057 quat 1 0 0 0 vel 0 0 -1.962 angvel 0 0 0", "off the grid", None),
]  # fmt: skip


def edit(text: str, start: str, new: str) -> tuple[str, int]:
    """``text`` with its first line starting with ``start`` replaced by ``new``; the line's number."""
    lines = text.splitlines()
    number = next(i for i, line in enumerate(lines) if line.startswith(start))
    lines[number] = new
    return "\n".join(lines) + "\n", number + 1


@pytest.mark.parametrize("start,new,field,token", EDITS, ids=[e[1][:40] for e in EDITS])
def test_an_edited_number_is_refused_at_its_line_and_field(start: str, new: str, field: str,
                                                           token: str | None) -> None:  # fmt: skip
    text, number = edit(dumps(recording()), start, new)
    with pytest.raises(BaselineError) as caught:
        loads(text, "g.golden")
    message = str(caught.value)
    column = new.index(token) + 1 if token is not None else None
    where = f"g.golden:{number}:{column}: " if column is not None else f"g.golden:{number}: "
    assert message.startswith(where) and field in message, message


def test_deeply_nested_json_in_a_var_line_is_refused_at_its_line() -> None:
    text, number = edit(dumps(recording()), "var 0 door_open", "var 0 door_open " + "[" * 100_000 + "]" * 100_000)
    with pytest.raises(BaselineError, match=rf"^g\.golden:{number}: cannot read this line"):
        loads(text, "g.golden")


def test_more_samples_than_a_golden_file_holds_are_refused_before_any_is_made() -> None:
    text, number = edit(dumps(recording()), "steps ", f"steps {MAX_SAMPLES * 2}")
    text = text.replace("every 2\n", "every 1\n")
    with pytest.raises(BaselineError, match=rf"^g\.golden:{number}: steps {MAX_SAMPLES * 2} sampled every 1"):
        loads(text, "g.golden")


def test_nan_stays_a_value_where_a_joint_records_it() -> None:
    """A joint without a motor records its motor force as NaN: a golden file holds it, as written."""
    rec = loads(dumps(recording()), "g.golden")
    assert all(v != v for v in rec.joints["slider"][:, 2])


DROP = """\
schema_version: 1
scenario: drop
world: {gravity: [0, 0, -9.81], dt: 0.01, duration: 0.5}
bodies:
  ball: {sphere: 0.1, density: 1000, pos: [0, 0, 2]}
"""


@pytest.mark.parametrize("start,new,field", [("every ", "every 0", "`every`"), ("dt ", "dt 0", "`dt`"),
                                             ("format ", "format \N{SUPERSCRIPT TWO}", "`format`")])  # fmt: skip
def test_check_refuses_an_edited_golden_file_with_exit_2(tmp_path: Path, start: str, new: str, field: str) -> None:
    def scenario(*args: str) -> subprocess.CompletedProcess[str]:
        return subprocess.run([sys.executable, "-m", "runner", *args], capture_output=True, text=True,
                              cwd=tmp_path, timeout=120)  # fmt: skip

    (tmp_path / "drop.yaml").write_text(DROP)
    recorded = scenario("baseline", "drop.yaml", "--backend", "fake", "--baseline", "b")
    assert recorded.returncode == 0, recorded.stdout + recorded.stderr
    (golden,) = (tmp_path / "b").iterdir()
    assert scenario("check", "drop.yaml", "--backend", "fake", "--baseline", "b", "--out", "t").returncode == 0
    text, number = edit(golden.read_text(), start, new)
    golden.write_text(text)
    done = scenario("check", "drop.yaml", "--backend", "fake", "--baseline", "b", "--out", "t")
    assert done.returncode == 2 and "Traceback" not in done.stderr, done.stdout + done.stderr
    assert f"{golden.name}:{number}:{new.index(' ') + 2}: {field}" in done.stdout + done.stderr, done.stderr


def test_a_nan_tolerance_no_longer_hides_a_difference(tmp_path: Path) -> None:
    """The probe's case: `atol=nan` made a 5.7 m difference "match"; it is refused at its line."""
    text = dumps(recording()).replace("tolerance default atol=1e-06 rtol=1e-06", "tolerance pos atol=nan")
    text = text.replace("body 0.2 box pos 0 0 1.7057", "body 0.2 box pos 0 0 7.4057")
    with pytest.raises(BaselineError, match=r"g\.golden:\d+:\d+: `tolerance pos atol`: expected a finite number"):
        loads(text, "g.golden")


def test_a_subnormal_dt_refuses_the_first_time_it_cannot_count_in_steps() -> None:
    """`dt 1e-320` is a number > 0, but 0.2 s is then inf steps (it was an OverflowError, exit 70)."""
    text = dumps(recording()).replace("dt 0.1\n", "dt 1e-320\n")
    number = next(i for i, line in enumerate(text.splitlines(), 1) if line.startswith("body 0.2 box"))
    with pytest.raises(BaselineError, match=rf"^g\.golden:{number}:6: body time: 0\.2 s is more than"):
        loads(text, "g.golden")
