"""Build every output of a comparison report from files: report.json, report.html, report.md and the
pictures the markdown shows (``report-images/``).

``write_report(paths, out_dir)`` is what ``scenario report`` and ``scenario compare`` both call, so a
comparison's report and one rebuilt later from its traces are the same function of the same files (and
the same bytes). report.json is the comparison document (docs/report-schema.md, checked by
docs/report.schema.json) as deterministic text: keys in the document's order, compact separators,
floats as Python's shortest repr, no NaN (missing values are null), UTF-8. Every file is written beside
its final name and renamed into place; pictures left from an earlier report are removed.
"""

from __future__ import annotations

import json
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from reports.compare_data import build_document
from reports.html import LAYOUT_NAME, render_html
from reports.markdown import IMAGES_DIR, markdown_images, render_markdown
from reports.runs import ReportError, Run, load_runs
from reports.scene_pictures import CasePictures, case_pictures
from reports.truth import Reference

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


def _write(path: Path, data: str | bytes) -> None:
    tmp = path.with_name(path.name + ".partial")
    if isinstance(data, str):
        tmp.write_text(data, encoding="utf-8")
    else:
        tmp.write_bytes(data)
    os.replace(tmp, path)


def _relative(target: Path, out_dir: Path) -> str:
    return Path(os.path.relpath(target.resolve(), out_dir.resolve())).as_posix()


def _links(doc: dict[str, Any], runs: Sequence[Run], out_dir: Path) -> tuple[list[dict[str, str | None]], str | None]:
    """Per case, backend -> the trace's path relative to ``out_dir``; and the Foxglove layout beside them."""
    by_key = {r.key: r for r in runs}
    out: list[dict[str, str | None]] = []
    folders: list[Path] = []
    for case in doc["cases"]:
        links: dict[str, str | None] = {}
        for r in case["runs"]:
            run = by_key.get((case["scenario"], case["variant"], r["backend"]))
            path = run.trace.path if run is not None and run.trace is not None else None
            links[r["backend"]] = _relative(path, out_dir) if path is not None else None
            if path is not None and path.parent not in folders:
                folders.append(path.parent)
        out.append(links)
    layout = next((f / LAYOUT_NAME for f in folders if (f / LAYOUT_NAME).is_file()), None)
    return out, _relative(layout, out_dir) if layout is not None else None


def _pictures(doc: dict[str, Any], runs: Sequence[Run]) -> list[CasePictures]:
    by_key = {r.key: r for r in runs}
    out = []
    for case in doc["cases"]:
        case_runs = {r["backend"]: by_key[(case["scenario"], case["variant"], r["backend"])]
                     for r in case["runs"] if (case["scenario"], case["variant"], r["backend"]) in by_key}  # fmt: skip
        out.append(case_pictures(case, case_runs))
    return out


def write_report(
    paths: list[Path],
    out_dir: Path,
    *,
    reference: str | None = None,
    max_divergence: float | None = None,
    references: Sequence[Reference] = (),
    require_agreement: bool = False,
) -> ReportFiles:
    """Read the runs named by ``paths`` (trace, partial trace, outcome or cost files, or folders) and
    write the reports into ``out_dir``; ``references`` are analytic truths (reports.truth.Reference)."""
    runs = load_runs(paths)
    doc = build_document(runs, reference=reference, max_divergence=max_divergence, references=references,
                         require_agreement=require_agreement)
    out_dir = Path(out_dir)
    try:
        out_dir.mkdir(parents=True, exist_ok=True)
        pictures = _pictures(doc, runs)
        links, layout = _links(doc, runs, out_dir)
        images = markdown_images(doc, pictures)
        files = ReportFiles(doc, out_dir / JSON_NAME, out_dir / HTML_NAME, out_dir / MD_NAME)
        folder = out_dir / IMAGES_DIR
        if images:
            folder.mkdir(exist_ok=True)
        for name, data in images.items():
            _write(folder / name, data)
        if folder.is_dir():
            for stale in folder.iterdir():
                if stale.is_file() and stale.name not in images:
                    stale.unlink()
        _write(files.json, dumps(doc))
        _write(files.markdown, render_markdown(doc, images, links, layout))
        _write(files.html, render_html(doc, runs, pictures, links, layout))
    except OSError as exc:
        raise ReportError(f"cannot write the report into {out_dir}: {exc.strerror or exc}") from exc
    return files
