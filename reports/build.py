"""Build every output of a comparison report from files: report.json, report.html, report.md and the
pictures the markdown shows (``report-images/``).

``write_report(paths, out_dir)`` is what ``scenario report`` and ``scenario compare`` both call, so a
comparison's report and one rebuilt later from its traces are the same function of the same files (and
the same bytes). report.json is the comparison document (docs/report-schema.md, checked by
docs/report.schema.json) as deterministic text: keys in the document's order, compact separators,
floats as Python's shortest repr, no NaN (missing values are null), UTF-8. Every file is written beside
its final name and renamed into place; pictures left from an earlier report are removed; nothing that is
not the tool's own is replaced or removed (reports.report_files).
"""

from __future__ import annotations

import json
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any
from urllib.parse import quote

from reports.compare_data import build_document
from reports.html import LAYOUT_NAME, render_html
from reports.imports import sections_beside
from reports.imports_render import html_section, markdown_section
from reports.markdown import markdown_images, render_markdown
from reports.report_files import (
    HTML_NAME,
    IMAGES_DIR,
    JSON_NAME,
    MD_NAME,
    foreign,
    refusal,
    remove_stale_images,
    tag_png,
    write_file,
)
from reports.runs import ReportError, Run, load_runs
from reports.scene_pictures import CasePictures, case_pictures
from reports.truth import Reference

__all__ = ["ReportError", "ReportFiles", "dumps", "write_report"]


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


def _relative(target: Path, out_dir: Path) -> str:
    """A link from the report to ``target``: relative, percent-encoded and prefixed ``./``, so that no
    folder's name (``javascript:alert(1)``) can read as a URL scheme, a query or a fragment."""
    return "./" + quote(Path(os.path.relpath(target.resolve(), out_dir.resolve())).as_posix(), safe="/")


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
    force: bool = False,
) -> ReportFiles:
    """Read the runs named by ``paths`` (trace, partial trace, outcome or cost files, or folders) and
    write the reports into ``out_dir``; ``references`` are analytic truths (reports.truth.Reference). How each
    engine imported the robots (``imports.json`` beside the traces, written by `scenario compare`) is added
    to the Markdown and the HTML. Files
    in ``out_dir`` that this tool did not write are refused (:mod:`reports.report_files`) unless ``force``."""
    runs = load_runs(paths)
    doc = build_document(runs, reference=reference, max_divergence=max_divergence, references=references,
                         require_agreement=require_agreement)
    out_dir = Path(out_dir)
    try:
        out_dir.mkdir(parents=True, exist_ok=True)
        pictures = _pictures(doc, runs)
        links, layout = _links(doc, runs, out_dir)
        images = {name: tag_png(png) for name, png in markdown_images(doc, pictures).items()}
        left = foreign(out_dir, images)
        if left and not force:
            raise ReportError(refusal(left))
        files = ReportFiles(doc, out_dir / JSON_NAME, out_dir / HTML_NAME, out_dir / MD_NAME)
        folder = out_dir / IMAGES_DIR
        if force and left:
            for path in left:
                if path.is_dir() and not path.is_symlink():
                    raise ReportError(f"cannot replace {path}: it is a folder")
                path.unlink()
        if images:
            folder.mkdir(exist_ok=True)
        for name, data in images.items():
            write_file(folder / name, data)
        remove_stale_images(folder, images)
        write_file(files.json, dumps(doc))
        imported = sections_beside([Path(p) for p in paths], {(c["scenario"], c["variant"]) for c in doc["cases"]})
        markdown = render_markdown(doc, images, links, layout) + "".join("\n" + markdown_section(s) for s in imported)
        write_file(files.markdown, markdown)
        write_file(files.html, render_html(doc, runs, pictures, links, layout, "".join(map(html_section, imported))))
    except OSError as exc:
        raise ReportError(f"cannot write the report into {out_dir}: {exc.strerror or exc}") from exc
    return files
