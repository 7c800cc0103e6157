"""Vega-Lite charts rendered by vl-convert: static SVG and PNG, and the Vega-Embed bundle to inline.

vl-convert (the Vega project's converter) runs Vega-Lite and Vega in an embedded JavaScript engine, so
static images need no browser and the same spec gives the same bytes (SVG ids renumbered per document).
For interactive pages each chart is given to Vega-Embed (with Vega-Lite, Vega and the Vega tooltip),
which comes from vl-convert's own bundle, gzipped (the page inflates it with the browser's
DecompressionStream: about 300 kB instead of 900 kB). The bundle's ``vega`` and ``vegaLite`` globals
are not usable (null), ``vegaEmbed`` is.
"""

from __future__ import annotations

import base64
import gzip
import json
import re
from functools import lru_cache
from importlib.metadata import version
from typing import Any

import vl_convert as vlc

__all__ = ["RUNTIME_SNIPPET", "png", "runtime_gzip_base64", "svg", "to_vega", "versions"]

#: what the inlined bundle defines: ``window.vegaEmbed``
RUNTIME_SNIPPET = "window.vegaEmbed = vegaEmbed;"


def _text(spec: dict[str, Any]) -> str:
    return json.dumps(spec, separators=(",", ":"), allow_nan=False, sort_keys=True)


_IDS = re.compile(r"\b(clip|gradient|pattern)(\d+)\b")


def _renumber(text: str) -> str:
    """Vega numbers clip paths and gradients with a counter that lives as long as the process; number them
    from 1 in order of appearance, so a chart's SVG does not depend on the charts drawn before it."""
    seen: dict[str, str] = {}

    def one(m: re.Match[str]) -> str:
        return seen.setdefault(m.group(0), f"{m.group(1)}{sum(k.startswith(m.group(1)) for k in seen) + 1}")

    return _IDS.sub(one, text)


def svg(spec: dict[str, Any]) -> str:
    """The chart as an SVG document (the same bytes for the same spec)."""
    return _renumber(vlc.vegalite_to_svg(_text(spec)))


def png(spec: dict[str, Any], scale: float = 1.0) -> bytes:
    """The chart as a PNG image."""
    return bytes(vlc.vegalite_to_png(_text(spec), scale=scale))


def to_vega(spec: dict[str, Any]) -> dict[str, Any]:
    """The chart compiled to a Vega spec (what the page's runtime draws)."""
    return dict(json.loads(json.dumps(vlc.vegalite_to_vega(_text(spec)))))


@lru_cache(maxsize=1)
def runtime_gzip_base64() -> str:
    """Vega-Embed with Vega-Lite and Vega (vl-convert's bundle), gzipped (no timestamp), base64-encoded."""
    code = vlc.javascript_bundle(RUNTIME_SNIPPET).encode("utf-8")
    return base64.b64encode(gzip.compress(code, compresslevel=9, mtime=0)).decode("ascii")


def versions() -> dict[str, str]:
    return {"vega": vlc.get_vega_version(), "vl-convert": version("vl-convert-python")}
