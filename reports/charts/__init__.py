"""The project's one charting path: Vega-Lite specs (:mod:`.specs`), one look per backend (:mod:`.style`),
rendered by vl-convert to SVG/PNG or drawn in the page by the inlined Vega-Embed bundle (:mod:`.render`).

Used by the comparison report (interactive charts, static PNG for the markdown report), the golden-file
divergence plot (runner.ci.golden_plot) and the sweep plot (``scenario sweep``).
"""
