"""The energy watchdog on robot links (runner.sim.energy): each body's energy at its centre of mass with its
full inertia tensor in world axes, checked against the energy computed independently from the trace.

The model is scenarios/robots/pendulum5.urdf: five links whose centres of mass sit off their link frames
(0.15 m down, 1 cm aside), whose inertial frames are turned (rpy) and whose tensors have off-diagonal terms,
on joints with alternating axes, so the swing is three-dimensional and every term of the energy counts.
The independent energy reads the URDF with yourdfpy (not the runner's loader) and the trace's link states
(pos, quat, vel, angvel of each link frame), and uses rotation matrices where the watchdog uses
quaternion products:

    E = sum_links 1/2 m |v + w x R o|^2 + 1/2 w^T (R R_o I R_o^T R^T) w + m g (p + R o)_z

(o, R_o: the URDF's inertial origin and rotation; I: its tensor). Nothing drives the chain, nothing
touches it (URDF links do not touch each other by default) and its joints are ideal, so E is conserved up
to the integrators' error.
"""

from __future__ import annotations

import numpy as np
import pytest

from backends.registry import KNOWN_BACKENDS, is_installed
from backends.types import BodyStates
from reports.trace_reader import Trace, read_trace
from runner.compile.program import build_program
from runner.language.load import load_scenario
from runner.sim.energy import GAIN_FRACTION, EnergyWatch, body_energies
from runner.sim.run import run_loaded
from tests.paths import ROOT

pytestmark = pytest.mark.slow
SCENARIO = ROOT / "scenarios" / "robots" / "pendulum5.yaml"
URDF = ROOT / "scenarios" / "robots" / "pendulum5.urdf"
ENGINES = [n for n, e in KNOWN_BACKENDS.items() if not (e.hidden or e.opt_in) and is_installed(n)]
G = 9.81


@pytest.fixture(scope="module", params=ENGINES)
def run(request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory) -> tuple[str, Trace]:
    """pendulum5 on one engine: it runs to its end (the watchdog does not stop it), with its trace."""
    engine = str(request.param)
    result = run_loaded(load_scenario(SCENARIO), engine, tmp_path_factory.mktemp(engine))
    assert result.status == "passed", result.failure
    assert result.trace is not None
    return engine, read_trace(result.trace)


def _matrix(q: np.ndarray) -> np.ndarray:
    """(S, 3, 3) rotation matrices of (S, 4) unit quaternions (w, x, y, z), normalised first."""
    q = q / np.linalg.norm(q, axis=1, keepdims=True)
    w, x, y, z = q.T
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], axis=-1),
            np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], axis=-1),
            np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], axis=-1),
        ],
        axis=-2,
    )


def _independent(trace: Trace) -> tuple[np.ndarray, np.ndarray]:
    """(kinetic, total) energy of the chain at every traced time, from the URDF and the trace (docstring)."""
    import yourdfpy

    robot = yourdfpy.URDF.load(str(URDF), build_scene_graph=False, load_meshes=False).robot
    kinetic = np.zeros(len(trace.times))
    total = np.zeros(len(trace.times))
    for link in robot.links:
        if link.inertial is None:
            continue
        m, origin, tensor = float(link.inertial.mass), np.asarray(link.inertial.origin), link.inertial.inertia
        s = trace.bodies[f"p.{link.name}"]
        r = _matrix(s.quat)
        offset = r @ origin[:3, 3]  # (S, 3): link origin -> COM, world axes
        v_com = s.vel + np.cross(s.angvel, offset)
        turn = r @ origin[:3, :3]
        world_tensor = turn @ np.asarray(tensor) @ np.transpose(turn, (0, 2, 1))
        k = 0.5 * m * np.einsum("si,si->s", v_com, v_com) + 0.5 * np.einsum("si,sij,sj->s", s.angvel, world_tensor,
                                                                              s.angvel)  # fmt: skip
        kinetic += k
        total += k + m * G * (s.pos[:, 2] + offset[:, 2])
    return kinetic, total


def _watchdog(trace: Trace, at_frames: bool = False) -> np.ndarray:
    """The watchdog's total energy of the same states (``at_frames``: as it was before it took each body's
    COM and inertia axes, the link frame as the centre of mass and the principal moments along its axes)."""
    world = build_program(load_scenario(SCENARIO)).world
    watch = EnergyWatch(world, "trace")
    names = [world.bodies[i].name for i in watch.index]
    series = [trace.bodies[n] for n in names]
    out = np.zeros(len(trace.times))
    for k in range(len(trace.times)):
        states = BodyStates(
            np.array([s.pos[k] for s in series]),
            np.array([s.quat[k] for s in series]),
            np.array([s.vel[k] for s in series]),
            np.array([s.angvel[k] for s in series]),
        )
        com, tensor = (None, None) if at_frames else (watch.com, watch.tensor)
        _, energy = body_energies(states, slice(None), watch.mass, watch.inertia, watch.gravity, com, tensor)
        out[k] = energy.sum()
    return out


def test_the_watchdog_energy_is_the_energy_from_the_trace(run: tuple[str, Trace]) -> None:
    """Both are float64 sums of products of the same numbers (the trace's states), which agree to rounding,
    except that the traced quaternions are unit only to the engine's precision (float32 on ODE: |q|^2 - 1 up
    to 2 ulps, 2.4e-7) and the watchdog turns vectors without normalising: each COM offset and rotational
    term is then off by up to 2.4e-7 of itself, so the sum by at most 2.4e-7 (max |E| + max K). Measured:
    5.2e-7 J on ODE, 2.6e-9 J on the float64 engines, of ~60 J."""
    _, trace = run
    kinetic, truth = _independent(trace)
    ours = _watchdog(trace)
    bound = 2.4e-7 * (float(np.max(np.abs(truth))) + float(np.max(kinetic)))
    assert np.max(np.abs(ours - truth)) <= bound


def test_the_pendulum_conserves_its_energy_within_the_watchdog_bound(run: tuple[str, Trace]) -> None:
    """The real energy (independent) never rises above its start by more than the integrator error the
    watchdog allows, GAIN_FRACTION (0.25) of the largest kinetic energy (docs/semantics.md, "Energy watchdog")."""
    engine, trace = run
    kinetic, total = _independent(trace)
    rise = float(np.max(total - total[0]))
    assert rise <= GAIN_FRACTION * float(np.max(kinetic)), f"{engine}: energy rose {rise:.4g} J"


def test_the_link_frame_energy_is_wrong_by_joules(run: tuple[str, Trace]) -> None:
    """The watchdog before: the link frame taken as the centre of mass (0.15 m off on each of 4 kg of links)
    and the inertia axes ignored: off by more than 1 J somewhere in the swing (the issue measured a false
    15.8 J gain on a 5-link pendulum), so the test above can tell the two apart."""
    _, trace = run
    _, truth = _independent(trace)
    assert np.max(np.abs(_watchdog(trace, at_frames=True) - truth)) > 1.0
