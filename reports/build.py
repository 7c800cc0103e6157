"""Build every output of a comparison report from files: report.json, report.html, report.md.

``write_report(paths, out_dir)`` is what ``scenario report`` and ``scenario compare`` both call, so a
comparison's report and one rebuilt later from its traces are the same function of the same files.
report.json is the comparison document (docs/report-schema.md, checked by docs/report.schema.json) as
deterministic text: keys in the document's order, compact separators, floats as Python's shortest repr,
no NaN (missing values are null), UTF-8.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from reports.compare_data import build_document
from reports.html import render_html
from reports.markdown import render_markdown
from reports.runs import ReportError, load_runs

__all__ = ["ReportError", "ReportFiles", "dumps", "write_report"]

JSON_NAME, HTML_NAME, MD_NAME = "report.json", "report.html", "report.md"


@dataclass(frozen=True)
class ReportFiles:
    document: dict[str, Any]
    json: Path
    html: Path
    markdown: Path

    @property
    def passed(self) -> bool:
        return bool(self.document["passed"])


def dumps(doc: dict[str, Any]) -> str:
    """report.json's text for ``doc``."""
    return json.dumps(doc, separators=(",", ":"), allow_nan=False, ensure_ascii=False) + "\n"


def _write(path: Path, text: str) -> None:
    tmp = path.with_name(path.name + ".partial")
    tmp.write_text(text, encoding="utf-8")
    os.replace(tmp, path)


def write_report(
    paths: list[Path],
    out_dir: Path,
    *,
    reference: str | None = None,
    max_divergence: float | None = None,
) -> ReportFiles:
    """Read the runs named by ``paths`` (trace, partial trace, outcome or cost files, or folders) and
    write the three reports into ``out_dir``."""
    runs = load_runs(paths)
    doc = build_document(runs, reference=reference, max_divergence=max_divergence)
    out_dir = Path(out_dir)
    try:
        out_dir.mkdir(parents=True, exist_ok=True)
        files = ReportFiles(doc, out_dir / JSON_NAME, out_dir / HTML_NAME, out_dir / MD_NAME)
        _write(files.json, dumps(doc))
        _write(files.markdown, render_markdown(doc))
        _write(files.html, render_html(doc, runs))
    except OSError as exc:
        raise ReportError(f"cannot write the report into {out_dir}: {exc.strerror or exc}") from exc
    return files
