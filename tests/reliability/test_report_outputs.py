"""Report outputs (issue 31, item 5): `report` and `compare` write and remove only files they recognise as
their own, report.md shows every user string as text, links are relative and start with `./`, and an
output that cannot take the report is exit 74 with nothing half-written left.

Found by an outside probe: `report` deleted every other file in DIR/report-images and overwrote a report.md
it did not write; report.md inserted assertion names and known-limit text raw, so a scenario could plant a
fake "✅ PASS" heading, an unclosed `<!--` hiding the rest, remote images and `javascript:` links; traces in
a folder named `javascript:alert(…)` gave report.html an `href="javascript:…"`; `report` on a full disk
exited 2 and left `.partial` files.
"""

from __future__ import annotations

import html
import re
import subprocess
import sys
from pathlib import Path

import pytest
from markdown_it import MarkdownIt

from reports.report_files import is_own, tag_png
from tests.exec.exit_table import _limits, environment

from .test_output_safety import read_only_folder

#: strings a scenario may put in an assertion's name or a known limit's cause, each one Markdown or HTML
HOSTILE = [
    "## ✅ PASS",
    "<!-- hide",
    "![x](http://evil.example/x.png)",
    "<script>alert(1)</script>",
    "<a href='javascript:alert(1)'>x</a>",
    "`code` | pipe &amp; $x$ ~~s~~ *em* __b__ https://evil.example a@evil.example",
    "[PASS](javascript:alert(1)) <img src=http://evil.example/y.png>",
]
SOURCE = """\
schema_version: 1
scenario: hostile
world: {{gravity: [0, 0, -9.81], dt: 0.01, duration: 0.2}}
bodies:
  ball: {{sphere: 0.1, density: 1000, pos: [0, 0, 2]}}
assertions:
{failing}
  - name: {limited}
    at: end
    value: ball.pos.z
    near: 5
    tol: 0.1
    known_limits:
      fake: {{measured: 3, cause: {cause}, doc: docs/language.md#known-limits}}
"""


def quoted(text: str) -> str:
    return "'" + text.replace("'", "''") + "'"


def scenario(*args: str, cwd: Path, fsize: int | None = None) -> subprocess.CompletedProcess[str]:
    limits = {"fsize": fsize} if fsize is not None else {}
    return subprocess.run([sys.executable, "-m", "runner", *args], capture_output=True, text=True, cwd=cwd,
                          timeout=180, env=environment(), preexec_fn=lambda: _limits(limits))  # fmt: skip


@pytest.fixture(scope="module")
def traces(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A trace of the hostile scenario (fake backend) in a folder named ``javascript:alert(1)``."""
    base = tmp_path_factory.mktemp("hostile")
    failing = "\n".join(f"  - {{name: {quoted(h)}, at: end, check: time < 0}}" for h in HOSTILE[:5])
    (base / "hostile.yaml").write_text(SOURCE.format(failing=failing, limited=quoted(HOSTILE[5]),
                                                     cause=quoted(HOSTILE[6])))  # fmt: skip
    done = scenario("run", "hostile.yaml", "--backend", "fake", "--out", "javascript:alert(1)", cwd=base)
    assert done.returncode == 1, done.stdout + done.stderr  # the assertions fail, as written
    return base / "javascript:alert(1)"


def report(traces: Path, out: Path, *extra: str, fsize: int | None = None) -> subprocess.CompletedProcess[str]:
    return scenario("report", str(traces), "--out", str(out), *extra, cwd=traces.parent, fsize=fsize)


def files(folder: Path) -> dict[str, bytes]:
    return {p.relative_to(folder).as_posix(): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def test_report_md_renders_every_user_string_as_text(traces: Path, tmp_path: Path) -> None:
    done = report(traces, tmp_path / "rep")
    assert done.returncode == 1, done.stderr
    text = (tmp_path / "rep" / "report.md").read_text(encoding="utf-8")
    rendered = MarkdownIt("commonmark").enable(["table", "strikethrough"]).render(text)
    for hostile in HOSTILE:  # each one shown as itself, HTML-escaped by the renderer like any text
        assert html.escape(hostile, quote=False) in rendered, (hostile, rendered)
    # what markup the page has is the report's own: 1 heading h2, its h3 sections, its pictures and links
    assert re.findall(r"<h(\d)>", rendered) == ["2", "3", "3", "3"]
    assert "<!--" not in rendered.replace("&lt;!--", "") and "<script" not in rendered
    assert not re.search(r"<(em|del)>", rendered) and "<strong>✅" not in rendered
    assert re.findall(r"<code>([^<]*)</code>", rendered) == ["report.html", "report.json"]  # the report's own
    assert re.findall(r'<img src="([^"]*)"', rendered) and all(
        src.startswith("./report-images/") for src in re.findall(r'<img src="([^"]*)"', rendered))  # fmt: skip
    hrefs = re.findall(r'<a href="([^"]*)"', rendered)
    assert hrefs and all(h.startswith("./") and ":" not in h for h in hrefs), hrefs


def test_links_in_report_html_are_relative_and_start_with_dot_slash(traces: Path, tmp_path: Path) -> None:
    done = report(traces, tmp_path / "rep")
    assert done.returncode == 1, done.stderr
    page = (tmp_path / "rep" / "report.html").read_text(encoding="utf-8")
    hrefs = [h for h in re.findall(r'href="([^"]*)"', page) if not h.startswith(("#", "data:"))]
    folder = "/javascript%3Aalert%281%29/"
    assert sorted(h[h.index(folder) :] for h in hrefs if h.startswith("./../") and folder in h) == [
        f"{folder}foxglove-layout.json", f"{folder}hostile__base__fake.mcap"], hrefs  # fmt: skip
    assert len(hrefs) == 2
    assert "javascript:alert" not in "".join(re.findall(r'(?:href|src)="([^"]*)"', page))


@pytest.mark.parametrize("name", ["report.md", "report.json", "report.html", "report-images/00-base-deviation.png"])
def test_a_users_file_named_like_a_report_file_is_refused(traces: Path, tmp_path: Path, name: str) -> None:
    out = tmp_path / "rep"
    (out / name).parent.mkdir(parents=True)
    (out / name).write_bytes(b"\x89PNG\r\n\x1a\n someone's picture" if name.endswith(".png") else b"my notes\n")
    before = files(out)
    done = report(traces, out)
    assert done.returncode == 2 and "Traceback" not in done.stderr, done.stdout + done.stderr
    assert f"{out / name} was not written by scenario and would be overwritten" in done.stderr, done.stderr
    assert "--force" in done.stderr and files(out) == before  # nothing written, nothing removed
    compared = scenario("compare", str(traces.parent / "hostile.yaml"), "--backends", "fake", "--out", str(out),
                        cwd=tmp_path)  # fmt: skip
    if name.startswith("report."):  # `compare` refuses it before any run
        assert compared.returncode == 2 and "was not written by scenario" in compared.stderr, compared.stderr
        assert files(out) == before
    forced = report(traces, out, "--force")
    assert forced.returncode == 1 and is_own(out / name), forced.stderr


def test_a_folder_of_the_users_files_as_out_keeps_every_file(traces: Path, tmp_path: Path) -> None:
    """`--out` a folder holding the user's files, report-images/ included: none is overwritten or removed;
    a picture of an earlier report that the new one does not show is removed (it is the tool's own)."""
    out = tmp_path / "mine"
    (out / "report-images").mkdir(parents=True)
    (out / "notes.md").write_text("# my notes\n")
    (out / "report-images" / "holiday.png").write_bytes(b"\x89PNG\r\n\x1a\n mine")
    (out / "report-images" / "99-old-deviation.png").write_bytes(b"\x89PNG\r\n\x1a\n mine too")
    (out / "report-images" / "readme.txt").write_text("keep\n")
    users = files(out)
    first = report(traces, out)
    assert first.returncode == 1, first.stderr
    written = files(out)
    assert {k: v for k, v in written.items() if k in users} == users
    assert {"report.md", "report.json", "report.html"} <= set(written)
    pictures = [k for k in written if k.startswith("report-images/") and k not in users]
    assert pictures and all(is_own(out / k) for k in pictures)
    stale = out / "report-images" / "00-stale-deviation.png"
    stale.write_bytes((out / pictures[0]).read_bytes())  # a picture an earlier report left
    again = report(traces, out)
    assert again.returncode == 1 and not stale.exists(), again.stderr
    assert {k: v for k, v in files(out).items() if k in users} == users
    assert files(out) == written  # the same report, byte for byte


def test_a_read_only_report_folder_is_an_output_error(traces: Path, tmp_path: Path) -> None:
    with read_only_folder(tmp_path / "ro") as out:
        done = report(traces, out)
        assert done.returncode == 74, done.stdout + done.stderr
        assert f"output error: cannot write the report into {out}" in done.stderr, done.stderr
        assert "Traceback" not in done.stderr and list(out.iterdir()) == []
    done = report(traces, tmp_path / "ro" / "sub")  # a folder it must make in it
    assert done.returncode in (0, 1)  # the folder writable again: the report is written


@pytest.mark.parametrize("fsize", [100, 20_000])
def test_a_full_disk_under_the_report_is_exit_74_and_leaves_no_partial(traces: Path, tmp_path: Path,
                                                                       fsize: int) -> None:  # fmt: skip
    """A file-size limit (EFBIG, any user) stops a picture (100 bytes) or report.html (20 kB) half-written."""
    out = tmp_path / "rep"
    done = report(traces, out, fsize=fsize)
    assert done.returncode == 74, done.stdout + done.stderr
    assert f"output error: cannot write the report into {out}: File too large" in done.stderr, done.stderr
    assert "Traceback" not in done.stderr
    left = [p.name for p in out.rglob("*")]
    assert not [n for n in left if "partial" in n], left
    assert "report.html" not in left


def test_pictures_carry_the_tools_mark_and_only_they_are_its_own(tmp_path: Path) -> None:
    png = b"\x89PNG\r\n\x1a\n" + b"\x00\x00\x00\x0dIHDR" + bytes(13) + b"\x00\x00\x00\x00"
    (tmp_path / "a.png").write_bytes(tag_png(png + b"rest"))
    (tmp_path / "b.png").write_bytes(png + b"rest")
    assert is_own(tmp_path / "a.png") and not is_own(tmp_path / "b.png")
    (tmp_path / "c.png").symlink_to(tmp_path / "a.png")
    assert not is_own(tmp_path / "c.png")  # a link under an output name is never the tool's
