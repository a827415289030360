"""Compiled geometry of the robot world: distances, line of sight, ray casting, time of impact, one sensor scan."""

from __future__ import annotations

import math

import numba as nb
import numpy as np

# Sensor constants (5.2.1; R: docs/RECONSTRUCTION.md, "HEROINE robot world"), re-exported by
# ``connrl.envs.robot.constants``. They are defined here because the cached kernels below compile them in, and
# Numba's cache notices an edit of this file only (issue 25; tests/nets/test_kernel_cache.py).
RAY_STEP_DEG = 15.0  # the N_RAYS sonar / light readings are 15 deg apart (5.2.1)
SONAR_MAX = 127  # sonar range 0..127 in, 1-in resolution (5.2.1)
SONAR_ERROR = 0.10  # reading uniform in [0.9x, 1.1x] (5.2.1)
DROPOUT_PROB = 0.25  # one reading of every 4 scans set to 127 (5.2.1)
LIGHT_HALF_ANGLE = 7.5  # light bit k on when the light is within +-7.5 deg of ray k (R)
LIGHT_RANGE = 120.0  # light detectable up to this distance from the centre (R)

# Segment kinds.
SEG_WALL, SEG_OBSTACLE, SEG_CHARGER = 0, 1, 2


# ---------------------------------------------------------------------------------------------------
# Numba kernels (all rays vs all segments in compiled loops; ~1-3 us per call)
@nb.njit(cache=True)
def _point_segments_distance(px, py, segs):
    best = np.inf
    for i in range(segs.shape[0]):
        ax, ay, bx, by = segs[i, 0], segs[i, 1], segs[i, 2], segs[i, 3]
        ex, ey = bx - ax, by - ay
        ll = ex * ex + ey * ey
        s = 0.0 if ll == 0.0 else ((px - ax) * ex + (py - ay) * ey) / ll
        s = min(1.0, max(0.0, s))
        dx, dy = ax + s * ex - px, ay + s * ey - py
        d = math.sqrt(dx * dx + dy * dy)
        if d < best:
            best = d
    return best


@nb.njit(cache=True)
def _segment_blocked(x0, y0, x1, y1, segs, kinds):
    """Does the open segment (x0,y0)-(x1,y1) cross a non-charger segment?"""
    dx, dy = x1 - x0, y1 - y0
    for i in range(segs.shape[0]):
        if kinds[i] == SEG_CHARGER:
            continue
        ax, ay = segs[i, 0], segs[i, 1]
        ex, ey = segs[i, 2] - ax, segs[i, 3] - ay
        den = dx * ey - dy * ex
        if den == 0.0:
            continue
        wx, wy = ax - x0, ay - y0
        t = (wx * ey - wy * ex) / den
        s = (wx * dy - wy * dx) / den
        if 0.0 < t < 1.0 and 0.0 <= s <= 1.0:
            return True
    return False


@nb.njit(cache=True)
def _cast_rays(x, y, heading_deg, segs, out):
    """Centre-to-surface distance along each of the 24 rays (inf when nothing is hit)."""
    for k in range(out.shape[0]):
        a = math.radians(heading_deg + RAY_STEP_DEG * k)
        dx, dy = math.cos(a), math.sin(a)
        best = np.inf
        for i in range(segs.shape[0]):
            ax, ay = segs[i, 0], segs[i, 1]
            ex, ey = segs[i, 2] - ax, segs[i, 3] - ay
            den = dx * ey - dy * ex
            if den == 0.0:
                continue
            wx, wy = ax - x, ay - y
            t = (wx * ey - wy * ex) / den
            if t <= 0.0 or t >= best:
                continue
            s = (wx * dy - wy * dx) / den
            if 0.0 <= s <= 1.0:
                best = t
        out[k] = best


@nb.njit(cache=True)
def _time_of_impact(x, y, dx, dy, segs, radius):
    """First contact of a disc moving from (x,y) by (dx,dy) with any segment.

    Returns (t, cx, cy, i): t in [0, 1] of first contact (t > 1: no contact), the contact point and
    the segment index.
    """
    best_t, bcx, bcy, bi = 2.0, 0.0, 0.0, -1
    a = dx * dx + dy * dy
    if a == 0.0:
        return best_t, bcx, bcy, bi
    r2 = radius * radius
    for i in range(segs.shape[0]):
        ax, ay, bx, by = segs[i, 0], segs[i, 1], segs[i, 2], segs[i, 3]
        # Endpoints: |p + t d - P| = r.
        for e in range(2):
            qx, qy = (ax, ay) if e == 0 else (bx, by)
            fx, fy = x - qx, y - qy
            b = 2.0 * (fx * dx + fy * dy)
            c = fx * fx + fy * fy - r2
            if c <= 0.0:
                t = 0.0 if b < 0.0 else 2.0  # already touching: only moving closer counts
            else:
                disc = b * b - 4.0 * a * c
                t = 2.0 if disc < 0.0 else (-b - math.sqrt(disc)) / (2.0 * a)
            if 0.0 <= t < best_t:
                best_t, bcx, bcy, bi = t, qx, qy, i
        # Interior: signed distance to the supporting line reaches +-r with the foot inside the segment.
        ex, ey = bx - ax, by - ay
        ln = math.sqrt(ex * ex + ey * ey)
        if ln == 0.0:
            continue
        ux, uy = ex / ln, ey / ln
        nx, ny = -uy, ux
        s0 = nx * (x - ax) + ny * (y - ay)
        sd = nx * dx + ny * dy
        side = 1.0 if s0 >= 0.0 else -1.0
        if side * sd >= 0.0:
            continue  # moving parallel to or away from the line
        t = (side * radius - s0) / sd
        if t < 0.0:
            t = 0.0 if abs(s0) <= radius else 2.0
        if t < best_t:
            cx = x + t * dx - side * radius * nx
            cy = y + t * dy - side * radius * ny
            proj = ux * (cx - ax) + uy * (cy - ay)
            if 0.0 <= proj <= ln:
                best_t, bcx, bcy, bi = t, cx, cy, i
    return best_t, bcx, bcy, bi


@nb.njit(cache=True)
def _scan(x, y, heading_deg, segs, kinds, lx, ly, radius, sonar_radius, u, noise, edge_jump, edge_both, true_out,
          sonar_out, light_out, door_out):
    """One sensor sweep: true body ranges, noisy sonar (measured from ``sonar_radius`` off the centre: the body's
    radius, or 0 for the centre), light bits and door-edge bits (the nearer reading of a jump, or ``edge_both``)."""
    n = true_out.shape[0]
    _cast_rays(x, y, heading_deg, segs, true_out)
    for k in range(n):
        raw = true_out[k]
        true_out[k] = min(min(max(raw - radius, 0.0), 1e6), float(SONAR_MAX))
        r = min(max(raw - sonar_radius, 0.0), 1e6)
        if noise:
            r = r * (1.0 - SONAR_ERROR + 2.0 * SONAR_ERROR * u[k])
        sonar_out[k] = min(float(SONAR_MAX), float(np.floor(r + 0.5)))
    if noise and u[n] < DROPOUT_PROB:
        sonar_out[min(int(u[n + 1] * n), n - 1)] = float(SONAR_MAX)
    # Light: one point source, thresholded direction bits.
    for k in range(n):
        light_out[k] = 0
    ddx, ddy = lx - x, ly - y
    if math.sqrt(ddx * ddx + ddy * ddy) <= LIGHT_RANGE and not _segment_blocked(x, y, lx, ly, segs, kinds):
        rel = math.degrees(math.atan2(ddy, ddx)) - heading_deg
        for k in range(n):
            diff = (rel - RAY_STEP_DEG * k + 180.0) % 360.0 - 180.0
            if abs(diff) <= LIGHT_HALF_ANGLE:
                light_out[k] = 1
    # Door edges: an abrupt jump between neighbours marks the nearer reading.
    for k in range(n):
        door_out[k] = 0
    for k in range(n):
        j = (k + 1) % n
        diff = sonar_out[k] - sonar_out[j]
        if edge_both and abs(diff) >= edge_jump:
            door_out[j] = 1
            door_out[k] = 1
        elif diff >= edge_jump:
            door_out[j] = 1
        elif -diff >= edge_jump:
            door_out[k] = 1


