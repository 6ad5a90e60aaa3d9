"""Small mechanisms for tests: one flexure between the ground and a tip body; an in-process
Dask client for the sweeps."""

from __future__ import annotations

import contextlib
from collections.abc import Iterator

import numpy as np

from flexval.geometry import Force, LoadCase, Material, Moment, Section
from flexval.geometry.mechanism import FlexureSpec, assemble
from flexval.reducedmodels.core.system import local_hessian


def cantilever(
    shape,
    E: float = 2100.0,
    b: float = 1.0,
    h: float = 0.1,
    nu: float = 0.3,
    clamped_end: int = 0,
    target_offset=(0.0, 0.0),
):
    """A flexure clamped to ground "g" at one end; the other end is body "t".

    The target point is the free end plus ``target_offset`` (mm).
    """
    ends = shape.end_points
    free = ends[1 - clamped_end]
    spec = FlexureSpec(
        "f", shape, ("g", "t"), Section(b, h), start_body="g" if clamped_end == 0 else "t"
    )
    return assemble(
        [spec],
        "g",
        ends[clamped_end][None],
        Material(E, nu),
        "t",
        free + np.asarray(target_offset, float),
    )


def tip_force(mech, fx: float, fy: float, levels: int = 11, name: str = "F") -> LoadCase:
    """Dead force (fx, fy) in N at the target point."""
    mag = float(np.hypot(fx, fy))
    return LoadCase(name, (Force("t", mech.target_point, float(np.arctan2(fy, fx)), mag),), levels)


def tip_moment(value: float, levels: int = 11, name: str = "M") -> LoadCase:
    """Moment (N mm) on the tip body."""
    return LoadCase(name, (Moment("t", value),), levels)


def fd_check(connector, pose_a, pose_b, internal, h: float = 1e-6):
    """Largest relative errors of gradient vs energy and Hessian vs gradient
    (central differences)."""
    q = np.concatenate([pose_a, pose_b, internal])
    n = q.size

    def split(v):
        return v[:3], v[3:6], v[6:]

    e0, g0, H0 = connector.evaluate(*split(q))
    H0 = local_hessian(connector, H0)
    H0 = H0.toarray() if hasattr(H0, "toarray") else H0
    g_fd = np.zeros(n)
    H_fd = np.zeros((n, n))
    for k in range(n):
        dq = np.zeros(n)
        dq[k] = h
        ep, gp, _ = connector.evaluate(*split(q + dq))
        em, gm, _ = connector.evaluate(*split(q - dq))
        g_fd[k] = (ep - em) / (2 * h)
        H_fd[:, k] = (gp - gm) / (2 * h)
    eg = np.abs(g_fd - g0).max() / max(np.abs(g0).max(), 1e-300)
    eh = np.abs(H_fd - H0).max() / max(np.abs(H0).max(), 1e-300)
    return eg, eh, np.abs(H0 - H0.T).max() / np.abs(H0).max()


def assembled_one_by_one(
    system, q: np.ndarray, loads, factor: float
) -> tuple[float, np.ndarray, np.ndarray]:
    """Energy (N mm), gradient and dense tangent of ``system`` at q, assembled the plain way.

    Every connector's own ``evaluate`` scattered densely through its local-to-global map,
    plus the loads: the independent reference of the System's grouped, compiled or
    slot-scattered assembly.
    """
    n = system.n_dofs
    energy, grad, tangent = 0.0, np.zeros(n), np.zeros((n, n))
    for conn, idx, local in zip(system.connectors, system.local_to_global, system.local_states(q)):
        e, g, h = conn.evaluate(*local)
        h = local_hessian(conn, h)
        h = h.toarray() if hasattr(h, "toarray") else h
        keep = idx >= 0
        energy += e
        np.add.at(grad, idx[keep], g[keep])
        tangent[np.ix_(idx[keep], idx[keep])] += h[np.ix_(keep, keep)]
    diagonal = np.zeros(n)
    energy += loads.add_to(q, factor, grad, diagonal)
    tangent[np.diag_indices(n)] += diagonal
    return energy, grad, tangent


def assert_assembles_like_its_connectors(
    system, q: np.ndarray, loads, factor: float
) -> tuple[np.ndarray, np.ndarray]:
    """Check ``system.assemble`` at q against :func:`assembled_one_by_one`; return its
    reference (gradient, dense tangent).

    The same sums in another order: round-off only (1e-16 of the largest entries;
    1e-13 allowed, relative to the energy and to the largest gradient and tangent entry).
    """
    energy, grad, tangent = system.assemble(q, loads, factor)
    ref_energy, ref_grad, ref_tangent = assembled_one_by_one(system, q, loads, factor)
    assert abs(energy - ref_energy) <= 1e-13 * abs(ref_energy)
    np.testing.assert_allclose(grad, ref_grad, rtol=0, atol=1e-13 * np.abs(ref_grad).max())
    np.testing.assert_allclose(
        tangent.toarray(), ref_tangent, rtol=0, atol=1e-13 * np.abs(ref_tangent).max()
    )
    return ref_grad, ref_tangent


@contextlib.contextmanager
def in_process_client() -> Iterator:
    """A Dask client of one in-process worker with one thread (no dashboard): a sweep's
    tasks run in the test's own process."""
    from distributed import Client, LocalCluster

    with (
        LocalCluster(
            n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None
        ) as cluster,
        Client(cluster) as client,
    ):
        yield client


def tiny_scene(name: str = "tiny", material: str = "", force: float = 0.01) -> str:
    """Scene TOML of one half-circle arc (radius 2 mm, h = 0.2 mm) between the ground and a
    tip link, with a force case ``up`` (``force`` N, upwards) and a moment case ``twist``
    (0.02 N mm); ``material`` adds lines to its ``[material]`` table."""
    extra = f"{material.strip()}\n" if material.strip() else ""
    return f"""
name = "{name}"
description = "one arc cantilever with a link"
[material]
youngs_modulus = 2000.0
poisson_ratio = 0.3
{extra}[section]
depth = 1.0
thickness = 0.2
[ground]
name = "g"
points = [[0.0, 0.0]]
[target]
body = "t"
point = [6.0, 0.0]
[[flexures]]
name = "a"
bodies = ["g", "t"]
center = [2.0, 0.0]
radius = 2.0
axis_deg = 90.0
width_deg = 180.0
[[load_cases]]
name = "up"
kind = "force"
angle_deg = 90.0
value = {force}
levels = 6
[[load_cases]]
name = "twist"
kind = "moment"
body = "t"
value = 0.02
levels = 6
"""


def with_sections_scaled(mechanism, factors):
    """Copies of ``mechanism`` with every flexure's section scaled by each factor in turn (a
    batch of copies that part ways)."""
    import dataclasses

    return [
        dataclasses.replace(
            mechanism,
            flexures=tuple(
                dataclasses.replace(f, section=f.section.scaled(s)) for f in mechanism.flexures
            ),
        )
        for s in factors
    ]
