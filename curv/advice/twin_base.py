"""The surfaces a twin's heights are measured from: a plane, or a sphere where the patch is curved.

A patch's twin is ``X(s, t) = base(s, t) + height g(s, t)`` along the base's normal, ``g`` a
polynomial (:mod:`curv.advice.twin_fit`). Over the tangent plane of its centre (``X = p + rho (s e1
+ t e2 + g n)``) a curved patch needs high-degree terms to bend (a sphere's cap over 70 degrees is
far from any low polynomial), and with noise their coefficients are noisy: the twin's curvature then
wavers at the candidates' own scale, and the candidates are judged against that. Measured from a
sphere of the patch's own mean curvature, ``X = c + (R + rho g) D(s, t)`` with ``D`` the unit
direction at tangent coordinates ``(rho s / R, rho t / R)``, a sphere needs no term at all and an
ellipsoid or torus far fewer. Patches
bending less than :data:`SPHERE_MIN` over their radius keep the plane (a sphere of huge radius
would lose precision for nothing). The sphere is fitted to the patch's points (Kasa's algebraic fit,
exact on a sphere); it need not pass through the centre, whose direction from the sphere's centre is
the base's axis.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Bases", "choose_bases", "SPHERE_MIN", "SPHERE_COSINE", "principal_from_derivatives"]

SPHERE_MIN = 0.02
"""A patch is measured from a sphere where ``|H| * radius`` (its mean curvature times its radius)
exceeds this."""

SPHERE_COSINE = 0.2
"""Points of a sphere-based patch farther than about 78 degrees from its axis seen from the sphere's
centre are left out (the tangent coordinates stop being one-to-one there)."""


def principal_from_derivatives(xs, xt, xss, xst, xtt, normal):
    """(k1, k2) of a parametrised surface from its derivatives at a point (rows: points).

    ``k`` are the eigenvalues of ``-I^-1 II`` (positive where the surface bends away from
    ``normal``), with ``I`` and ``II`` the fundamental forms of the derivatives (paper eq. 2.1-2.3).
    """
    e, f, g = (np.einsum("ij,ij->i", a, b) for a, b in ((xs, xs), (xs, xt), (xt, xt)))
    l, m, n = (np.einsum("ij,ij->i", a, normal) for a in (xss, xst, xtt))
    det = e * g - f * f
    h = -(e * n - 2.0 * f * m + g * l) / (2.0 * det)
    k = (l * n - m * m) / det
    disc = np.sqrt(np.maximum(h * h - k, 0.0))
    return h + disc, h - disc


def _unit(v):
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


@dataclass(frozen=True)
class Bases:
    """The base of each of c patches.

    Attributes
    ----------
    origin : (c, 3) float64
        The centre vertex (the plane's origin; on the sphere at tangent coordinates 0).
    frame : (c, 3, 3) float64
        Rows ``e1, e2, axis`` (right-handed): the plane's normal, or the sphere's direction at the
        centre.
    radius : (c,) float64
        The patch's radius (the coordinates' unit).
    sphere : (c,) bool
        Which patches are measured from a sphere.
    centre : (c, 3) float64
        The sphere's centre (unused for planes).
    big : (c,) float64
        The sphere's radius (inf for planes).
    side : (c,) float64
        +1 or -1: the input's normal at the centre is ``side * axis``.
    plane_frame : (c, 3, 3) float64
        Each patch's plane frame (the base of a patch that is not on a sphere).
    """

    origin: np.ndarray
    frame: np.ndarray
    radius: np.ndarray
    sphere: np.ndarray
    centre: np.ndarray
    big: np.ndarray
    side: np.ndarray
    plane_frame: np.ndarray

    def restricted(self, sphere: np.ndarray) -> "Bases":
        """The same bases with only the patches ``sphere`` (c,) bool on a sphere, the rest on their
        planes (``plane_frame``: the rows e1, e2, n a plane needs, kept for this)."""
        keep = self.sphere & sphere
        return Bases(origin=self.origin, frame=np.where(keep[:, None, None], self.frame, self.plane_frame),
                     radius=self.radius, sphere=keep, centre=np.where(keep[:, None], self.centre, np.nan),
                     big=np.where(keep, self.big, np.inf), side=np.where(keep, self.side, 1.0),
                     plane_frame=self.plane_frame)

    def coordinates(self, i: int, points: np.ndarray):
        """Patch ``i``'s points in its base: ``s, t, z`` (m,) and which can be used (m,) bool."""
        e1, e2, axis = self.frame[i]
        rho = self.radius[i]
        if not self.sphere[i]:
            d = (points - self.origin[i]) / rho
            return d @ e1, d @ e2, d @ axis, np.ones(points.shape[0], bool)
        delta = points - self.centre[i]
        r = np.linalg.norm(delta, axis=1)
        d = delta / np.maximum(r, 1e-300)[:, None]
        scale = self.big[i] / rho
        return d @ e1 * scale, d @ e2 * scale, (r - self.big[i]) / rho, d @ axis > SPHERE_COSINE

    def surface(self, i: int, s, t, g, gs, gt):
        """Patch ``i``'s twin at ``(s, t)`` with heights ``g`` and slopes ``gs, gt`` (m,): positions (m, 3),
        unit normals on the input's side (m, 3), and the cosine between the height's direction and
        the normal (m,), which turns a height residual into a distance along the normal."""
        e1, e2, axis = self.frame[i]
        rho = self.radius[i]
        if not self.sphere[i]:
            x = self.origin[i] + rho * (s[:, None] * e1 + t[:, None] * e2 + g[:, None] * axis)
            normal = _unit(axis - gs[:, None] * e1 - gt[:, None] * e2)
            return x, normal, normal @ axis
        lam = rho / self.big[i]
        u, v = lam * s, lam * t
        w = np.sqrt(np.maximum(1.0 - u * u - v * v, 1e-12))
        d = u[:, None] * e1 + v[:, None] * e2 + w[:, None] * axis
        q = self.big[i] + rho * g
        xs = rho * gs[:, None] * d + (q * lam)[:, None] * (e1 - (u / w)[:, None] * axis)
        xt = rho * gt[:, None] * d + (q * lam)[:, None] * (e2 - (v / w)[:, None] * axis)
        normal = self.side[i] * _unit(np.cross(xs, xt))
        return self.centre[i] + q[:, None] * d, normal, np.abs(np.einsum("ij,ij->i", d, normal))

    def centre_curvature(self, fits) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """k1, k2 (c,) and the unit normal (c, 3) on the input's side of each twin at its centre."""
        e1, e2, axis = self.frame[:, 0], self.frame[:, 1], self.frame[:, 2]
        rho = self.radius[:, None]
        g0, gs, gt = (fits.at_origin(i, j)[:, None] for i, j in ((0, 0), (1, 0), (0, 1)))
        gss, gst, gtt = (fits.at_origin(i, j)[:, None] for i, j in ((2, 0), (1, 1), (0, 2)))
        plane = ~self.sphere[:, None]
        lam = np.where(plane, 0.0, rho / np.where(plane, 1.0, self.big[:, None]))
        q = np.where(plane, 1.0, self.big[:, None] + rho * g0)  # the plane's: X_s = rho (e1 + g_s n)
        xs = np.where(plane, rho * (e1 + gs * axis), rho * gs * axis + q * lam * e1)
        xt = np.where(plane, rho * (e2 + gt * axis), rho * gt * axis + q * lam * e2)
        xss = rho * gss * axis + np.where(plane, 0.0, 2 * rho * gs * lam * e1 - q * lam**2 * axis)
        xst = rho * gst * axis + np.where(plane, 0.0, rho * gs * lam * e2 + rho * gt * lam * e1)
        xtt = rho * gtt * axis + np.where(plane, 0.0, 2 * rho * gt * lam * e2 - q * lam**2 * axis)
        normal = self.side[:, None] * _unit(np.cross(xs, xt))
        k1, k2 = principal_from_derivatives(xs, xt, xss, xst, xtt, normal)
        return k1, k2, normal


GEOMETRIC_STEPS = 4
"""Gauss-Newton steps from Kasa's sphere to the sphere of least weighted squared distances."""


def _geometric_sphere(y, w, centre, big):
    """The sphere of least weighted squared (geometric) distances, from ``centre``, ``big`` (c, 3), (c,).

    Kasa's algebraic fit is exact on a sphere but biased off it (towards smaller spheres under
    noise); measured from it, a noisy sphere still needs quadratic terms, and a sphere with
    quadratic terms is no sphere: its curvature varies over the patch. From the geometric fit a
    spherical patch needs none (each is then within its noise and dropped)."""
    ok = np.isfinite(big)
    c, r = np.where(ok[:, None], centre, 0.0), np.where(ok, big, 1.0)
    for _ in range(GEOMETRIC_STEPS):
        d = y - c[:, None, :]
        dist = np.sqrt(np.maximum(np.sum(d * d, axis=-1), 1e-300))
        res = dist - r[:, None]
        jac = np.concatenate([-d / dist[..., None], -np.ones(dist.shape + (1,))], axis=-1)  # (c, N, 4)
        jw = jac * w[..., None]
        step = np.linalg.solve(np.swapaxes(jw, 1, 2) @ jac + 1e-12 * np.eye(4),
                               -(np.swapaxes(jw, 1, 2) @ res[..., None]))[..., 0]
        c, r = c + step[:, :3], r + step[:, 3]
    good = ok & np.isfinite(r) & (r > 0) & np.isfinite(c).all(axis=1)
    return np.where(good[:, None], c, centre), np.where(good, r, big)


def choose_bases(origin, frame, radius, s, t, z, w) -> Bases:
    """Each patch's base from its plane frame and a sphere fitted to its points.

    Parameters
    ----------
    origin : (c, 3) float64
        The centre vertices.
    frame : (c, 3, 3) float64
        Rows ``e1, e2, n`` of each patch's plane (``n`` on the input's side).
    radius : (c,) float64
    s, t, z, w : (c, N) float64
        The patches' points in their planes' coordinates (scaled by the radius) and their weights
        (0: padding).

    Returns
    -------
    Bases
        The sphere of least weighted squared distances (from Kasa's algebraic fit, ``|y|^2 + b.y +
        c = 0``, linear and exact for points on a sphere, by :data:`GEOMETRIC_STEPS` Gauss-Newton
        steps) where its curvature times the patch radius exceeds :data:`SPHERE_MIN`, the plane
        elsewhere (and where the fit fails).
    """
    c = len(radius)
    y = np.stack([s, t, z], axis=-1)  # (c, N, 3)
    design = np.concatenate([y, np.ones(s.shape + (1,))], axis=-1)  # (c, N, 4)
    dw = design * w[..., None]
    gram = np.swapaxes(dw, 1, 2) @ design + 1e-12 * np.eye(4)
    rhs = -(np.swapaxes(dw, 1, 2) @ np.sum(y * y, axis=-1)[..., None])[..., 0]
    try:
        sol = np.linalg.solve(gram, rhs[..., None])[..., 0]
    except np.linalg.LinAlgError:
        sol = np.full((c, 4), np.nan)
    centre = -0.5 * sol[:, :3]  # scaled, in the plane frame
    big2 = np.sum(centre * centre, axis=1) - sol[:, 3]
    big = np.sqrt(np.where(big2 > 0, big2, np.nan))
    centre, big = _geometric_sphere(y, w, centre, big)
    sphere = np.isfinite(big) & (1.0 / np.where(np.isfinite(big), big, np.inf) > SPHERE_MIN)
    side = np.where(centre[:, 2] < 0, 1.0, -1.0)  # centre below the input's side: bends away from it
    toward = -centre / np.maximum(np.linalg.norm(centre, axis=1), 1e-300)[:, None]  # centre -> origin
    axis = np.einsum("ci,cij->cj", toward, frame)
    e1 = _unit(frame[:, 0] - np.einsum("ij,ij->i", frame[:, 0], axis)[:, None] * axis)
    e2 = np.cross(axis, e1)
    world_centre = origin + radius[:, None] * np.einsum("ci,cij->cj", centre, frame)
    return Bases(origin=origin, frame=np.where(sphere[:, None, None], np.stack([e1, e2, axis], axis=1), frame),
                 radius=radius, sphere=sphere, centre=np.where(sphere[:, None], world_centre, np.nan),
                 big=np.where(sphere, big * radius, np.inf), side=np.where(sphere, side, 1.0), plane_frame=frame)
