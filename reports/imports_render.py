"""The import comparison (:mod:`reports.imports`) as terminal lines, Markdown and HTML.

A *section* is one case: ``scenario``, ``variant``, ``digits`` (the file's most precise number) and ``reads``
(one engine read per backend). Each quantity is one table: the rows where every engine agrees are collapsed to
their one value; the rows where engines differ show every engine's value, the departing ones flagged (``≠``).
"""

from __future__ import annotations

from html import escape
from typing import Any

from reports.imports import READ, ROUNDINGS, Table, compare
from reports.markdown_text import text as md

__all__ = ["flagged", "html_section", "markdown_section", "summary", "terminal_lines"]

FLAG = "≠ "
LEGEND = ("damping and friction: `engine` = the engine's own joint parameter, `runner` = the runner's motor "
          "(none on a joint a servo or motor drives); effort and velocity: the tighter of the engine's limit and "
          "the runner's cap")


def _tables(section: dict[str, Any]) -> list[Table]:
    return compare(section["reads"], int(section["digits"]))


def _backends(section: dict[str, Any]) -> list[str]:
    return [r["backend"] for r in section["reads"] if r.get("status") == READ]


def _others(section: dict[str, Any]) -> list[str]:
    """The engines that did not report, with why; and those that imported a world they would not run."""
    lines = [f"{r['backend']}: {r['status']}" + (f" ({r['message']})" if r.get("message") else "")
             for r in section["reads"] if r.get("status") != READ]  # fmt: skip
    return lines + [f"{r['backend']}: {r['runs']}" for r in section["reads"] if r.get("runs")]


def _engines(section: dict[str, Any]) -> str:
    parts = []
    for r in section["reads"]:
        if r.get("status") == READ:
            bits = 32 if float(r["eps"]) > 1e-10 else 64
            parts.append(f"{r['backend']} {r.get('version', '')} (float{bits})".replace("  ", " "))
    return ", ".join(parts)


def _rule(section: dict[str, Any]) -> str:
    return (f"agreement within {ROUNDINGS:g} eps of the coarser engine's float format, or half a unit in the "
            f"last of the file's {section['digits']} significant digits, relative to each value's scale")  # fmt: skip


def flagged(section: dict[str, Any]) -> list[tuple[str, str, int]]:
    """(quantity, engine, rows) for every engine flagged in a quantity."""
    out = []
    for table in _tables(section):
        counts: dict[str, int] = {}
        for row in table.rows:
            for backend, cell in row.cells.items():
                if cell.flagged:
                    counts[backend] = counts.get(backend, 0) + 1
        out += [(table.title, b, n) for b, n in counts.items()]
    return out


def summary(section: dict[str, Any]) -> str:
    """One line: what differs, or that the engines agree."""
    found = flagged(section)
    if not found:
        return f"the {len(_backends(section))} engines imported the model alike"
    return "differences: " + "; ".join(f"{q} on {b} ({n} row{'s' * (n > 1)})" for q, b, n in found)


def _uniform(table: Table) -> str | None:
    """The one value of a table whose rows all agree on the same value (collapsed to one line), else None."""
    values = {r.agreed() for r in table.rows}
    return values.pop() if not table.differences and len(values) == 1 else None


def _head(table: Table) -> str:
    unit = f" [{table.unit}]" if table.unit else ""
    same = _uniform(table)
    if same is not None:
        return f"{table.title}{unit}: all {len(table.rows)} agree: {same}"
    status = (f"{table.differences} of {len(table.rows)} differ" if table.differences
              else f"all {len(table.rows)} agree")  # fmt: skip
    return f"{table.title}{unit}: {status}"


def _cell(cell: Any) -> str:
    return (FLAG if cell.flagged else "") + cell.text if cell is not None else "–"


def terminal_lines(section: dict[str, Any]) -> list[str]:
    backends = _backends(section)
    out = [f"How each engine imported the robots of {section['scenario']} · {section['variant']} (before any step)",
           f"  engines: {_engines(section)}", f"  {_rule(section)}"]  # fmt: skip
    out += [f"  {line}" for line in _others(section)]
    for table in _tables(section):
        if not table.rows:
            continue
        out.append(f"  {_head(table)}")
        if _uniform(table) is not None:
            continue
        width = max(len(r.name) for r in table.rows)
        differ = [r for r in table.rows if not r.agree]
        for row in table.rows:
            if row.agree:
                out.append(f"    {row.name:<{width}}  {row.agreed()}")
        if differ:
            cols = [max([len(b)] + [len(_cell(r.cells.get(b))) for r in differ]) for b in backends]
            out.append(f"    {'':<{width}}  " + "  ".join(f"{b:<{w}}" for b, w in zip(backends, cols, strict=True)))
            for row in differ:
                cells = [_cell(row.cells.get(b)) for b in backends]
                padded = (f"{c:<{w}}" for c, w in zip(cells, cols, strict=True))
                out.append(f"    {row.name:<{width}}  " + "  ".join(padded))
    out.append(f"  {LEGEND}")
    out.append(f"  {summary(section)}")
    return [line.rstrip() for line in out]


def markdown_section(section: dict[str, Any]) -> str:
    backends = _backends(section)
    out = [f"## How each engine imported the robots: {md(section['scenario'])} · {md(section['variant'])}", "",
           f"Read back from each engine before any step: {md(_engines(section))}; {md(_rule(section))}. "
           f"{md(LEGEND)}. **{md(summary(section))}**", ""]  # fmt: skip
    out += [f"- {md(line)}" for line in _others(section)]
    for table in _tables(section):
        if not table.rows:
            continue
        out += [f"**{md(_head(table))}**", ""]
        if _uniform(table) is not None:
            continue
        differ = [r for r in table.rows if not r.agree]
        if differ:
            out += ["| " + " | ".join(["name", *(md(b) for b in backends)]) + " |", "|---" * (len(backends) + 1) + "|"]
            for row in differ:
                cells = []
                for b in backends:
                    cell = row.cells.get(b)
                    shown = "–" if cell is None else md(FLAG + cell.text) if cell.flagged else md(cell.text)
                    cells.append(f"**{shown}**" if cell is not None and cell.flagged else shown)
                out.append("| " + " | ".join([md(row.name), *cells]) + " |")
            out.append("")
        same = [r for r in table.rows if r.agree]
        if same:
            out += ["| name | every engine |", "|---|---|"]
            out += [f"| {md(r.name)} | {md(r.agreed())} |" for r in same]
            out.append("")
    return "\n".join(out) + "\n"


def html_section(section: dict[str, Any]) -> str:
    backends = _backends(section)
    parts = [f'<section class="imports"><h2>How each engine imported the robots: {escape(section["scenario"])} · '
             f'{escape(section["variant"])}</h2><p class="meta">Read back from each engine before any step: '
             f"{escape(_engines(section))}; {escape(_rule(section))}. {escape(LEGEND)}. "
             f"<b>{escape(summary(section))}</b></p>"]  # fmt: skip
    others = _others(section)
    if others:
        parts.append("<ul>" + "".join(f"<li>{escape(o)}</li>" for o in others) + "</ul>")
    for table in _tables(section):
        if not table.rows:
            continue
        if _uniform(table) is not None:
            parts.append(f"<h3>{escape(_head(table))}</h3>")
            continue
        head = "".join(f"<th>{escape(b)}</th>" for b in backends)
        rows = []
        for row in table.rows:
            if row.agree:
                rows.append(f'<tr><td>{escape(row.name)}</td><td colspan="{len(backends)}">{escape(row.agreed())}'
                            "</td></tr>")  # fmt: skip
                continue
            cells = []
            for b in backends:
                cell = row.cells.get(b)
                if cell is None:
                    cells.append("<td>–</td>")
                elif cell.flagged:
                    cells.append(f'<td style="background:#fdd"><b>{escape(FLAG + cell.text)}</b></td>')
                else:
                    cells.append(f"<td>{escape(cell.text)}</td>")
            rows.append(f'<tr><td>{escape(row.name)}</td>{"".join(cells)}</tr>')
        parts.append(f"<h3>{escape(_head(table))}</h3><table><tr><th>name</th>{head}</tr>{''.join(rows)}</table>")
    parts.append("</section>")
    return "".join(parts)
