"""MJCF's legacy dialect upgraded to what MuJoCo 4 reads, before MuJoCo's compiler sees the file.

Files written for older MuJoCo (and pybullet's `loadMJCF`, which still reads them) use constructs MuJoCo 4
refuses; 8 of pybullet_data's 26 MJCF files do. Each construct is converted as older MuJoCo, or pybullet's
loader, read it, and each conversion is a note on the model (``ModelDesc.notes``, shown by `scenario
inspect` and the survey), listed in docs/robots.md ("MJCF's legacy dialect"):

- `<compiler coordinate="global">`: rewritten in local frames (runner.language.mjcf_global);
- a joint of `type="fixed"` (pybullet's fixed joint; MuJoCo never had one): removed, so its body is welded to
  its parent (MuJoCo's body without a joint);
- an `<inertial>` without `pos`: at the body's origin (`pos="0 0 0"`, pybullet's default);
- a `material` naming no `<material>`: dropped (the geom keeps its rgba);
- `<option collision=...>`, which MuJoCo 3.0 removed, migrated as MuJoCo's changelog says: `all` dropped;
  `dynamic` drops every `<contact><pair>`; `predefined` (or `pair`) makes every geom's contype and conaffinity
  0, so only the explicit pairs collide;
- a tendon, actuator, equality or sensor naming a joint (or a tendon or actuator) that the file does not
  define: dropped with what depends on it (pybullet reads none of them);
- a plane geom without a positive third `size` (its grid spacing, drawn only): 1 m.

The upgraded text keeps every line where it was (removed elements leave their line breaks), so MuJoCo's
messages name the file's own lines. A file with none of these is handed to MuJoCo as it is.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from runner.language.mjcf_global import to_local
from runner.language.robot_desc import ModelFileError, resolved
from runner.language.urdf_xml import xml_bytes

LEGACY = "legacy MJCF"
#: the grid spacing given to a plane without one (MuJoCo draws its grid with it; no step reads it)
PLANE_GRID = 1.0
#: included files followed when collecting the names a file defines (as runner.language.mjcf_checks.MAX_INCLUDES)
MAX_INCLUDES = 64


@dataclass(frozen=True)
class Upgraded:
    """The file as MuJoCo 4 reads it: its text, the files its `<include>`s name (as written -> absolute path),
    and one note per conversion."""

    text: str
    includes: tuple[tuple[str, str], ...]
    notes: tuple[str, ...]


def _parse(file: Path) -> Any:
    from lxml import etree

    parser = etree.XMLParser(remove_comments=False, resolve_entities=False, no_network=True)
    try:
        return etree.fromstring(xml_bytes(file), parser)
    except etree.XMLSyntaxError as exc:
        line, column = exc.position if exc.position else (exc.lineno or 0, 0)
        raise ModelFileError(file, line or 0, f"malformed XML: {exc.msg}", column=column or 0) from None


def _elements(root: Any, *tags: str) -> list[Any]:
    return [e for e in root.iter(*tags) if isinstance(e.tag, str)]


def _remove(element: Any) -> None:
    """``element`` out of its parent, its line breaks kept in the text before what followed it."""
    from lxml import etree

    breaks = etree.tostring(element, encoding="unicode", with_tail=False).count("\n")
    keep = "\n" * breaks + (element.tail or "")
    parent, previous = element.getparent(), element.getprevious()
    if previous is not None:
        previous.tail = (previous.tail or "") + keep
    else:
        parent.text = (parent.text or "") + keep
    parent.remove(element)


def _includes(root: Any, file: Path) -> list[tuple[str, Path, Any]]:
    """Every file included, directly or not (relative to the main file's folder, as MuJoCo reads them):
    (as written, path, its root element); one that cannot be read is left to MuJoCo's own message."""
    out: list[tuple[str, Path, Any]] = []
    todo, seen = [root], {file.resolve()}
    while todo:
        for element in _elements(todo.pop(), "include"):
            name = element.get("file")
            if not name:
                continue
            path = resolved(file.parent / name, file, element.sourceline or 0, name)
            if path in seen or len(seen) >= MAX_INCLUDES or not path.is_file():
                continue
            seen.add(path)
            included = _parse(path)
            out.append((name, path, included))
            todo.append(included)
    return out


def _fixed_joints(root: Any, file: Path, notes: list[str]) -> None:
    for default in _elements(root, "default"):
        for joint in default.iterfind("joint"):
            if joint.get("type") == "fixed":
                raise ModelFileError(
                    file,
                    joint.sourceline or 0,
                    '<default> <joint type="fixed">: pybullet\'s '
                    "fixed joint as a default is not converted (write it on the joints)",
                    near="type",
                )
    for joint in _elements(root.find("worldbody") if root.find("worldbody") is not None else root, "joint"):
        if joint.get("type") == "fixed":
            body = joint.getparent().get("name") or "(unnamed)"
            notes.append(f"{LEGACY}: joint `{joint.get('name') or '(unnamed)'}` (line {joint.sourceline}) is "
                         f"`type=\"fixed\"`, which MuJoCo does not read: removed, so body `{body}` is welded to its "
                         "parent (pybullet's fixed joint)")  # fmt: skip
            _remove(joint)


def _inertials(root: Any, notes: list[str]) -> None:
    for inertial in _elements(root, "inertial"):
        if inertial.get("pos") is None and inertial.getparent().tag == "body":
            inertial.set("pos", "0 0 0")
            notes.append(f"{LEGACY}: <inertial> (line {inertial.sourceline}) has no `pos`, which MuJoCo requires: "
                         "at the body's origin, `pos=\"0 0 0\"` (pybullet's default)")  # fmt: skip


def _materials(root: Any, included: list[Any], notes: list[str]) -> None:
    names = {m.get("name") for tree in (root, *included) for m in _elements(tree, "material") if m.get("name")}
    for element in _elements(root):
        name = element.get("material")
        if name is not None and element.tag != "material" and name not in names:
            del element.attrib["material"]
            notes.append(
                f"{LEGACY}: <{element.tag}> (line {element.sourceline}) names material `{name}`, which "
                "the file does not define: dropped (its rgba stays; pybullet reads no materials)"
            )


def _option_collision(root: Any, notes: list[str]) -> None:
    for option in _elements(root, "option"):
        mode = option.attrib.pop("collision", None)
        if mode is None:
            continue
        line = option.sourceline
        if mode == "dynamic":
            for pair in _elements(root, "pair"):
                _remove(pair)
            what = "every <contact><pair> removed (only contype/conaffinity collisions)"
        elif mode in ("predefined", "pair"):
            for geom in _elements(root, "geom"):
                geom.attrib.pop("contype", None)
                geom.attrib.pop("conaffinity", None)
            _default_geom(root).attrib.update({"contype": "0", "conaffinity": "0"})
            what = "every geom's contype and conaffinity 0, so only the file's <contact><pair>s collide"
        else:
            what = "dropped (every collision, MuJoCo's default)"
        notes.append(f"{LEGACY}: <option collision=\"{mode}\"> (line {line}), which MuJoCo 3.0 removed: {what}, as "
                     "MuJoCo's changelog migrates it")  # fmt: skip


def _default_geom(root: Any) -> Any:
    """The top-level `<default>`'s own `<geom>` (added on the first line when there is none)."""
    from lxml import etree

    default = next((d for d in root.iterfind("default")), None)
    if default is None:
        default = etree.Element("default")
        default.tail, root.text = root.text, ""
        root.insert(0, default)
    geom = default.find("geom")
    if geom is None:
        geom = etree.SubElement(default, "geom")
    return geom


def _refers(element: Any, keys: tuple[str, ...], missing: set[str]) -> str | None:
    for key in keys:
        if element.get(key) is not None and element.get(key) in missing:
            return f"{key} `{element.get(key)}`"
    return None


def _dangling(root: Any, included: list[Any], notes: list[str]) -> None:
    """Tendons, actuators, equalities and sensors naming a joint the file does not define, dropped; then
    what names a dropped tendon or actuator."""
    trees = (root, *included)
    joints = {j.get("name") for t in trees for j in _elements(t, "joint", "freejoint")
              if j.get("name") and j.getparent().tag == "body"}  # fmt: skip
    referenced = {e.get(k) for e in _elements(root) for k in ("joint", "jointinparent", "joint1", "joint2")
                  if e.get(k) is not None and e.getparent() is not None and e.getparent().tag != "default"}  # fmt: skip
    missing = referenced - joints
    if not missing:
        return
    dropped: dict[str, set[str]] = {"tendon": set(), "actuator": set()}
    removed: dict[str, list[str]] = {}  # section -> "<tag> `name` (line N)" removed from it
    why_removed: dict[str, set[str]] = {}

    def drop(element: Any, why: str) -> None:
        kind = element.getparent().tag
        name = element.get("name")
        if name and kind in dropped:
            dropped[kind].add(name)
        removed.setdefault(kind, []).append(
            f"<{element.tag}>{f' `{name}`' if name else ''} (line {element.sourceline})"
        )
        why_removed.setdefault(kind, set()).add(why)
        _remove(element)

    for tendon in [t for section in root.iterfind("tendon") for t in section if isinstance(t.tag, str)]:
        bad = next((r for j in tendon.iterfind("joint") if (r := _refers(j, ("joint",), missing))), None)
        if bad:
            drop(tendon, bad)
    sections: list[tuple[str, tuple[str, ...], Callable[[], set[str]]]] = [
        ("equality", ("joint1", "joint2"), set),
        ("actuator", ("joint", "jointinparent"), lambda: dropped["tendon"]),
        ("sensor", ("joint",), lambda: dropped["tendon"] | dropped["actuator"]),
    ]
    for section, keys, also in sections:
        for element in [e for s in root.iterfind(section) for e in s if isinstance(e.tag, str)]:
            why = _refers(element, keys, missing) or _refers(element, ("tendon", "tendon1", "tendon2", "actuator"),
                                                             also())  # fmt: skip
            if why:
                drop(element, why)
    for kind, items in removed.items():
        names = ", ".join(sorted(why_removed[kind]))
        notes.append(
            f"{LEGACY}: {len(items)} in <{kind}> name what the file does not define ({names}): removed "
            f"(pybullet reads no <{kind}>): {', '.join(items)}"
        )


def _planes(root: Any, notes: list[str]) -> None:
    sized = any(g.get("size") is not None for d in _elements(root, "default") for g in d.iterfind("geom"))
    for geom in _elements(root.find("worldbody") if root.find("worldbody") is not None else root, "geom"):
        if geom.get("type") != "plane" or (geom.get("size") is None and sized):
            continue
        try:
            values = [float(v) for v in (geom.get("size") or "").split()]
        except ValueError:
            continue  # left to MuJoCo's message
        if len(values) >= 3 and values[2] > 0:
            continue
        values = (values + [0.0, 0.0])[:2] + [PLANE_GRID]
        geom.set("size", " ".join(repr(v) for v in values))
        notes.append(
            f"{LEGACY}: plane `{geom.get('name') or '(unnamed)'}` (line {geom.sourceline}) has no positive "
            f"third size (its grid spacing, drawn only), which MuJoCo now requires: {PLANE_GRID:g} m"
        )


def upgrade(file: Path) -> Upgraded | None:
    """``file`` upgraded from MJCF's legacy dialect (module docstring); None when nothing in it is legacy.
    A legacy construct that cannot be converted is a ModelFileError at its line."""
    from lxml import etree

    root = _parse(file)
    included = _includes(root, file)
    notes = to_local(root, file)
    _fixed_joints(root, file, notes)
    _inertials(root, notes)
    _materials(root, [tree for _, _, tree in included], notes)
    _option_collision(root, notes)
    _dangling(root, [tree for _, _, tree in included], notes)
    _planes(root, notes)
    if not notes:
        return None
    text = "\n" * ((root.sourceline or 1) - 1) + etree.tostring(root, encoding="unicode", with_tail=False)
    return Upgraded(text, tuple((name, str(path)) for name, path, _ in included), tuple(notes))
