"""Benchmark 8: the seed's own ODE loop against the runner on ODE, on the same pile.

The lab's pattern (``/work/shared/seed/``, the tutorial's last steps), written with panda3d.ode as the
lab wrote it with PyODE: each step ``space.collide((world, contactgroup), near_callback)``, where the
Python ``near_callback`` asks ``OdeUtil.collide(geom1, geom2, 150)`` for the contacts of one pair (150:
PyODE's ``ode.collide`` limit; a box pair gives at most 8) and makes them one by one: ``setBounce(0.2)``,
``setMu(5000)``, an ``OdeContactJoint`` attached to the two bodies; then ``world.step(dt)``, the contact
group emptied, and every body's pose read (the lab copies it to its visual model each frame).

It uses the pile's world (bench/scenarios/pile.yaml: box_pile's surface, bounce 0.2 above 0.1 m/s, mu
5000) with the adapter's ERP, CFM and stepper, so that both solve the same problem; the two differ in how
contacts are made (a Python callback per pair here, C++ in the adapter, the pile's `friction_pyramid:
axes`), so their final poses are reported, not required to agree. The runner writes its full trace; the
seed writes nothing. Interleaved repetitions, medians; build included in both.
"""

from __future__ import annotations

import gc
import statistics
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from runner.sim.run import run_loaded, trace_path

from . import measure as m

#: The lab's own loop is ODE's (panda3d.ode): this section is one engine's by definition, like raw_ode.py.
ENGINE = "ode"

TARGET = 5.0  # the runner (with its trace) at least this many times faster than the seed's loop
MAX_CONTACTS = 150  # PyODE's ode.collide


class SeedLoop:
    """The seed's loop (see the module docstring) on a compiled pile."""

    def __init__(self, world: Any, settings: dict[str, Any]) -> None:
        from panda3d.ode import OdeBoxGeom, OdeJointGroup, OdePlaneGeom, OdeSimpleSpace, OdeWorld

        from backends.types import Motion, ShapeKind

        from .raw_ode import ode_body

        self.h = world.dt
        self.collide_seconds = 0.0  # space.collide with the Python near-callback
        self.step_seconds = 0.0  # world.step and emptying the contact group
        self.world = w = OdeWorld()
        w.setGravity(*world.gravity)
        w.setErp(settings["erp"])
        w.setCfm(settings["cfm"])
        w.setQuickStepNumIterations(settings["quickstep_iterations"])
        self.stepper = w.step if settings["stepper"] == "dWorldStep" else w.quickStep
        self.space = OdeSimpleSpace()
        self.contactgroup = OdeJointGroup()
        self.bodies: list[Any] = []
        self.geoms: list[Any] = []
        surface = world.default_surface
        self.mu, self.bounce, self.bounce_vel = surface.mu, surface.bounce, surface.bounce_vel
        for b in world.bodies:
            if b.shape.kind is ShapeKind.PLANE:
                geom = OdePlaneGeom(self.space, 0.0, 0.0, 1.0, b.pos[2])
            else:
                geom = OdeBoxGeom(self.space, *b.shape.size)
            if b.motion is not Motion.STATIC:
                body = ode_body(w, b)
                geom.setBody(body)
                self.bodies.append(body)
            self.geoms.append(geom)

    def near_callback(self, args: Any, geom1: Any, geom2: Any) -> None:
        from panda3d.ode import OdeContact, OdeContactJoint, OdeSurfaceParameters, OdeUtil

        body1, body2 = geom1.getBody(), geom2.getBody()
        if body1.isEmpty() and body2.isEmpty():
            return
        entry = OdeUtil.collide(geom1, geom2, MAX_CONTACTS)  # the actual collisions between the two solids
        world, contactgroup = args
        for i in range(entry.getNumContacts()):
            c = OdeContact()
            c.setGeom(entry.getContactGeom(i))
            s = OdeSurfaceParameters()
            s.setMode(OdeSurfaceParameters.MFContactBounce)
            s.setBounce(self.bounce)  # how much bounce should happen from this collision
            s.setBounceVel(self.bounce_vel)
            s.setMu(self.mu)  # how much friction there should be between the solids
            c.setSurface(s)
            j = OdeContactJoint(world, contactgroup, c)  # a temporary joint joins the solids together
            j.attach(body1, body2)

    def step(self) -> None:
        t0 = time.perf_counter()
        self.space.collide((self.world, self.contactgroup), self.near_callback)
        t1 = time.perf_counter()
        self.stepper(self.h)
        self.contactgroup.empty()
        self.collide_seconds += t1 - t0
        self.step_seconds += time.perf_counter() - t1
        for body in self.bodies:  # the lab copies each pose to its visual model
            body.getPosition()
            body.getQuaternion()

    def positions(self) -> np.ndarray:
        return np.array([list(b.getPosition()) for b in self.bodies])

    def close(self) -> None:
        self.contactgroup.empty()
        for geom in self.geoms:
            geom.destroy()
        for body in self.bodies:
            body.destroy()
        self.space.destroy()
        self.world.destroy()


@dataclass
class SeedFigures:
    boxes: int
    steps: int
    seed: list[float] = field(default_factory=list)
    runner: list[float] = field(default_factory=list)
    status: str = ""
    collide: list[float] = field(default_factory=list)  # the seed's space.collide + near-callbacks, s
    solver: list[float] = field(default_factory=list)  # the seed's world.step, s
    distance: float = float("nan")  # largest distance between the two final box positions, m

    @property
    def ratio(self) -> float:
        return statistics.median(self.seed) / statistics.median(self.runner)


    @property
    def best_possible(self) -> float:
        """The ratio a runner costing nothing beyond the engine's own step could reach: seed / its world.step."""
        return statistics.median(self.seed) / statistics.median(self.solver)


def run_seed(world: Any, settings: dict[str, Any], steps: int, fig: SeedFigures) -> np.ndarray:
    gc.collect()
    start = time.perf_counter()
    loop = SeedLoop(world, settings)
    try:
        for _ in range(steps):
            loop.step()
        fig.seed.append(time.perf_counter() - start)
        fig.collide.append(loop.collide_seconds)
        fig.solver.append(loop.step_seconds)
        return loop.positions()
    finally:
        loop.close()


def run(counts: tuple[int, int, int], duration: float, reps: int, log: Callable[[str], None] = print) -> SeedFigures:
    loaded = m.pile(counts, duration)
    world, steps = m.world_of(loaded)
    settings = m.adapter_settings(ENGINE, world)
    fig = SeedFigures(len(world.bodies) - 1, steps)
    seed_final = None
    with tempfile.TemporaryDirectory(prefix="bench-seed-") as tmp:
        for rep in range(reps):
            for mode in ("seed", "runner") if rep % 2 == 0 else ("runner", "seed"):
                if mode == "seed":
                    seed_final = run_seed(world, settings, steps, fig)
                    continue
                gc.collect()
                start = time.perf_counter()
                result = run_loaded(loaded, ENGINE, Path(tmp))
                fig.runner.append(time.perf_counter() - start)
                fig.status = result.status
            log(f"  seed loop round {rep + 1}/{reps}: seed {fig.seed[-1]:.2f}s, runner+trace {fig.runner[-1]:.2f}s")
        final = m.final_from_trace(str(trace_path(Path(tmp), loaded, ENGINE)))[1:, :3]  # without the ground
    if seed_final is not None:
        fig.distance = float(np.abs(final - seed_final).max())
    return fig


def targets(fig: SeedFigures | None) -> list[str]:
    if fig is None:
        return []
    return [f"| ODE: the runner with its full trace >= {TARGET:g}x faster than the seed's loop (Python near-callback), "
            f"{fig.boxes} boxes | {fig.ratio:.1f}x | {'met' if fig.ratio >= TARGET else '**not met**'} "
            f"| {_cause(fig)} |"]  # fmt: skip


def _cause(fig: SeedFigures) -> str:
    seed = statistics.median(fig.seed)
    return (f"ODE's own world.step (dWorldStep) is {statistics.median(fig.solver) / seed:.0%} of the seed loop's "
            f"time and the Python near-callbacks {statistics.median(fig.collide) / seed:.0%}: the callbacks are all "
            f"a runner can save, so with a step as costly as the seed's it could be at most {fig.best_possible:.1f}x "
            f"faster; 5x is out of reach on this pile (section 9)")


def render(fig: SeedFigures | None) -> list[str]:
    if fig is None:
        return []
    seed, runner = statistics.median(fig.seed), statistics.median(fig.runner)
    return [
        "## 9. The seed's loop: the lab's own ODE pattern against the runner on ODE",
        "",
        "bench/seed_loop.py: `space.collide((world, contactgroup), near_callback)`, a Python near-callback that "
        "calls `OdeUtil.collide` for the pair and makes each contact joint (bounce, mu) one by one, "
        "`world.step`, the group emptied, every pose read: the lab's code on the same pile, with the adapter's "
        "ERP, CFM and stepper. The runner: `run_loaded` on ODE with its full trace (the pile's contacts are made "
        "in C++, `friction_pyramid: axes`). Build included; medians of interleaved repetitions.",
        "",
        "| boxes | steps | seed loop (s) | of which near-callbacks (s) | of which world.step (s) "
        "| runner + trace (s) | runner faster by | at most possible | final positions differ by (m) | runner status |",
        "|---|---|---|---|---|---|---|---|---|---|",
        f"| {fig.boxes} | {fig.steps} | {seed:.2f} | {statistics.median(fig.collide):.2f} "
        f"| {statistics.median(fig.solver):.2f} | {runner:.2f} | {fig.ratio:.2f}x | {fig.best_possible:.2f}x "
        f"| {fig.distance:.2g} | {fig.status} |",
        "",
        "*at most possible*: the seed loop's time over its `world.step` alone, what a runner costing nothing "
        "beyond a step as costly as the seed's would reach. The step (ODE's dWorldStep, the big LCP over every "
        "contact) is nearly the same work in both (the runner's contacts, made in C++ with the pile's "
        "`friction_pyramid: axes`, can make it a little cheaper, which is how the runner can beat this bound); "
        "the seed's Python near-callbacks are what the runner saves.",
        "",
    ]
