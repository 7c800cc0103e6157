"""The report's 3D scene (reports.scene3d) drawn by Panda3D's software renderer, offscreen.

Every check looks at real pixels: each body's colour (as lit: the same hue, darker or lighter) is found
where Panda3D's lens projects the body's centre; a ball resting on a tilted ramp is drawn in front of it
(the z-buffer, where sorting faces by their centres failed); a scale change after the start and a
translucent collision solid are drawn from the trace's scene channel. Skipped only without Panda3D.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from reports.scene3d import CameraSpec, SceneModel, frame_camera, scene_model
from reports.scene3d.model import BodyTrack, EntityVisual, Primitive
from reports.trace_reader import read_trace

pytest.importorskip("panda3d.core", reason="engine not installed: panda3d (the ode extra)")

from reports.scene3d.offscreen import OffscreenRenderer  # noqa: E402
from reports.scene3d.panda import PandaScene  # noqa: E402

HERE = Path(__file__).parent
W, H = 300, 200


@pytest.fixture(scope="module")
def renderer() -> OffscreenRenderer:
    return OffscreenRenderer(W, H)


def lit_like(pixel: np.ndarray, rgb: tuple[float, float, float]) -> bool:
    """``pixel`` (0..255) is ``rgb`` (0..1) lit by some amount: k * rgb within 14 levels, k in [0.3, 1.1]."""
    c = np.asarray(rgb, float) * 255
    k = float(pixel @ c) / float(c @ c)
    return 0.3 <= k <= 1.1 and float(np.max(np.abs(pixel - k * c))) <= 14


def found_near(image: np.ndarray, px: np.ndarray, rgb: tuple[float, float, float], radius: int = 3) -> bool:
    x, y = int(round(px[0])), int(round(px[1]))
    window = image[max(y - radius, 0) : y + radius + 1, max(x - radius, 0) : x + radius + 1].reshape(-1, 3)
    return any(lit_like(p.astype(float), rgb) for p in window)


def _spec(name: str, shape: dict, pos: list[float], color: list[float], motion: str = "dynamic",
          quat: tuple[float, ...] = (1.0, 0.0, 0.0, 0.0)) -> dict:  # fmt: skip
    return {"name": name, "motion": motion, "pos": pos, "quat": list(quat), "color": color,
            "shape": {"kind": "box", "size": [0, 0, 0], "radius": 0.0, "length": 0.0, **shape}}  # fmt: skip


def _still(model: SceneModel, specs: list[dict], times: tuple[float, ...] = (0.0, 1.0)) -> SceneModel:
    t = np.asarray(times)
    for s in specs:
        model.tracks[s["name"]] = BodyTrack(t, np.tile(s["pos"], (len(t), 1)), np.tile(s["quat"], (len(t), 1)))
    model.end_time = float(t[-1])
    return model


def test_every_body_shows_its_colour_where_the_lens_puts_it(renderer: OffscreenRenderer) -> None:
    specs = [
        _spec("floor", {"kind": "plane"}, [0, 0, 0], [0.55, 0.6, 0.55], "static"),
        _spec("crate", {"kind": "box", "size": [0.6, 0.6, 0.6]}, [0, 0, 0.3], [0.85, 0.6, 0.3]),
        _spec("ball", {"kind": "sphere", "radius": 0.25}, [1.2, 0.3, 0.25], [0.9, 0.15, 0.1]),
        _spec("can", {"kind": "cylinder", "radius": 0.2, "length": 0.5}, [-1.0, 0.6, 0.25], [0.2, 0.35, 0.75]),
        _spec("pill", {"kind": "capsule", "radius": 0.12, "length": 0.4}, [0.4, 1.2, 0.12], [0.3, 0.7, 0.3],
              quat=(0.7071068, 0.7071068, 0.0, 0.0)),
    ]  # fmt: skip
    model = _still(SceneModel.from_specs(specs), specs)
    for s in specs[1:]:  # they move (a little): the camera frames them
        model.tracks[s["name"]].pos = model.tracks[s["name"]].pos + [[0, 0, 0], [0.05, 0, 0]]
    scene = PandaScene(model)
    camera = frame_camera([model])
    scene.show(0.0)
    image = np.asarray(renderer.render(scene, camera))
    centres = renderer.project(scene, camera, [s["pos"] for s in specs[1:]])
    for s, px in zip(specs[1:], centres, strict=True):
        assert np.isfinite(px).all(), s["name"]
        assert found_near(image, px, s["color"]), f"{s['name']} not drawn at {px}"
    floor = np.mean([lit_like(p.astype(float), specs[0]["color"]) for p in image.reshape(-1, 3)])
    assert floor > 0.2  # the plane fills the background below the horizon
    again = np.asarray(renderer.render(scene, camera))
    assert np.array_equal(image, again)  # the same pixels every time


def test_a_ball_on_a_tilted_ramp_is_drawn_in_front_of_it(renderer: OffscreenRenderer) -> None:
    trace = read_trace(_run(HERE / "scenarios" / "ball_on_ramp.yaml", "ode"))
    model = scene_model(trace)
    scene = PandaScene(model)
    camera = frame_camera([model])
    ball = next(b for b in model.bodies if b == "ball")
    for t in (0.0, 0.6, model.end_time):
        scene.show(t)
        image = np.asarray(renderer.render(scene, camera))
        pose = model.pose(ball, t)
        assert pose is not None
        px = renderer.project(scene, camera, [pose[0]])[0]
        assert found_near(image, px, model.color[ball][:3]), f"the ball is not drawn at t = {t}"
        ramp = renderer.project(scene, camera, [model.pose("ramp", t)[0]])[0]
        assert found_near(image, ramp, model.color["ramp"][:3], radius=6)


def test_scale_changes_and_collision_solids_come_from_the_scene_channel(renderer: OffscreenRenderer) -> None:
    trace = read_trace(_run(HERE / "scenarios" / "growing_box.yaml", "fake"))
    model = scene_model(trace)
    start, end = model.entities_at(0.0), model.entities_at(model.end_time)
    assert start["body/box"].primitives[0].size == pytest.approx((0.3, 0.3, 0.3))
    assert end["body/box"].primitives[0].size == pytest.approx((0.9, 0.9, 0.9))
    solid = start["solid/box/box"]
    assert solid.solid and solid.primitives[0].kind == "sphere" and solid.primitives[0].rgba[3] < 1
    scene = PandaScene(model)
    camera = frame_camera([model])
    box = np.asarray(model.color["box"][:3])

    def box_pixels(t: float) -> int:
        scene.show(t)
        image = np.asarray(renderer.render(scene, camera)).reshape(-1, 3).astype(float)
        return sum(lit_like(p, tuple(box)) for p in image)

    scene.set_solids_visible(False)  # the amber solid around the small box would tint it
    small, big = box_pixels(0.0), box_pixels(model.end_time)
    assert 4 < big / small < 16  # three times the edge: about nine times the area, give or take perspective
    # the translucent solid (radius 0.3 at the start) around the 0.3 m box tints the background amber
    scene.show(0.0)
    centre = renderer.project(scene, camera, [model.pose("box", 0.0)[0]])[0]
    bare = np.asarray(renderer.render(scene, camera)).astype(int)
    scene.set_solids_visible(True)
    scene.show(0.0)
    image = np.asarray(renderer.render(scene, camera)).astype(int)
    x, y = int(centre[0]), int(centre[1])
    ring = image[y - 40 : y + 40, x - 40 : x + 40] - bare[y - 40 : y + 40, x - 40 : x + 40]
    tinted = np.abs(ring).sum(axis=2) > 20
    assert tinted.sum() > 100  # the solid shows
    assert (ring[tinted][:, 0] >= ring[tinted][:, 2]).all()  # towards amber: red up (or kept), blue down


def test_a_model_without_a_scene_channel_uses_the_metadata_shapes() -> None:
    specs = [_spec("crate", {"kind": "box", "size": [0.5, 0.4, 0.3]}, [0, 0, 0], [1, 0, 0])]
    model = SceneModel.from_specs(specs)
    entity = model.entities_at(0.0)["body/crate"]
    cube = Primitive("cube", (1.0, 0.0, 0.0, 1.0), size=(0.5, 0.4, 0.3))
    assert entity == EntityVisual("body/crate", "crate", (cube,))


def _run(path: Path, backend: str) -> Path:
    from backends.registry import is_installed
    from runner.language.load import load_scenario
    from runner.sim.run import run_loaded

    if not is_installed(backend):
        pytest.skip(f"engine not installed: {backend}")
    out = Path(__import__("tempfile").mkdtemp(prefix="reports-scene3d-"))
    result = run_loaded(load_scenario(path, None), backend, out)
    assert result.trace is not None
    return Path(result.trace)


#: kuka_iiwa/model.urdf's materials (Blue links 1, 2, 4, 5; Orange links 3, 6; Grey 0) and the scenario's red link 7
KUKA_BLUE, KUKA_ORANGE, KUKA_RED = (0.5, 0.7, 1.0), (1.0, 0.423529411765, 0.0392156862745), (0.9, 0.2, 0.2)
PATCH = 25  # pixels: a colour counts as drawn when it covers at least a 5 x 5 patch


def test_a_robot_is_drawn_by_its_visual_meshes_in_their_materials(renderer: OffscreenRenderer) -> None:
    """The KUKA arm's pictures show the URDF's <visual> meshes in their materials' colours (not the collision
    hulls in one grey); its collision shapes (/scene/collision) are there but hidden until asked for."""
    model = scene_model(read_trace(_run(HERE.parents[1] / "scenarios" / "robots" / "kuka_arm.yaml", "pybullet")))
    at_start = model.entities_at(0.0)
    assert {e.layer for e in at_start.values()} == {"body", "joint", "collision"}
    scene = PandaScene(model)
    camera = frame_camera([model])
    scene.show(model.end_time)
    image = np.asarray(renderer.render(scene, camera)).astype(float)
    pixels = image.reshape(-1, 3)
    for rgb in (KUKA_BLUE, KUKA_ORANGE, KUKA_RED):
        assert sum(lit_like(p, rgb) for p in pixels) >= PATCH, rgb
    scene.set_collision_visible(True)  # the translucent amber hulls over the meshes change the arm's pixels
    scene.show(model.end_time)
    hulls = np.asarray(renderer.render(scene, camera)).astype(float)
    assert int((np.abs(hulls - image).sum(axis=2) > 20).sum()) >= PATCH


def test_a_body_casts_its_shadow_where_the_light_projects_it(renderer: OffscreenRenderer) -> None:
    """A cube 1 m above the floor: where the directional light projects its centre onto the floor the picture is
    the floor's colour lit by the ambient light alone (the shadow is drawn unlit in that colour: within 2 of 255
    levels, 8-bit rounding and the supersampling filter); a point half as far on the other side of the cube is
    the lit floor. A scene without a floor below its bodies has no shadows."""
    from reports.scene3d.panda import AMBIENT

    floor_rgb = (0.55, 0.6, 0.55)
    specs = [
        _spec("floor", {"kind": "plane"}, [0, 0, 0], list(floor_rgb), "static"),
        _spec("cube", {"kind": "box", "size": [0.6, 0.6, 0.6]}, [0, 0, 1.0], [0.85, 0.6, 0.3]),
    ]
    model = _still(SceneModel.from_specs(specs), specs)
    scene = PandaScene(model)
    assert scene.shadows is not None
    camera = CameraSpec((0.0, -5.0, 3.0), 0.0, -25.0, (60.0, 40.0))  # the cube, its shadow and the floor around
    scene.show(0.0)
    image = np.asarray(renderer.render(scene, camera)).astype(float)
    d = np.asarray(scene.lights[1].getQuat(scene.root).getForward())
    centre = np.array([0.0, 0.0, 1.0])
    shadow = centre - d * centre[2] / d[2]  # along the light down to z = 0
    lit = centre - (shadow - centre) * [0.5, 0.5, 0] - [0, 0, 1.0]  # on the floor, half as far the other way
    px_shadow, px_lit = renderer.project(scene, camera, [shadow.tolist(), lit.tolist()])
    assert np.isfinite(px_shadow).all() and np.isfinite(px_lit).all()
    in_shadow = image[int(round(px_shadow[1])), int(round(px_shadow[0]))]
    assert in_shadow == pytest.approx(np.asarray(floor_rgb) * AMBIENT * 255, abs=2)
    on_floor = image[int(round(px_lit[1])), int(round(px_lit[0]))]
    assert lit_like(on_floor, floor_rgb) and on_floor.mean() > in_shadow.mean() + 20  # the sun's share
    flying = [specs[1]]
    assert PandaScene(_still(SceneModel.from_specs(flying), flying)).shadows is None
