"""numba kernels: one projection kernel and one residual kernel per constraint kind.

Every kernel works on the arrays of :class:`layout.model.Model` (packed as named
tuples) and on the state arrays ``pos (n, 3)`` and ``yaw (n,)``. Corrections always go
to a particle's *body* (itself, or the rigid group it is fixed to), so rigid groups
move as one. In Gauss–Seidel mode a correction is written at once; in Jacobi mode it
is added to ``acc`` and :func:`flush` applies the average of each batch
(one constraint kind) with over-relaxation ω.

Formulas follow Weiss et al. 2018 (TVCG) Sec. 3 and the thesis Ch. 5; the equation
numbers in comments are the paper's. Kernels use numpy's error model (a division by
zero gives inf, never an exception check in the hot loop); every division that could
see a zero is guarded. Degenerate cases (a zero-length direction) are
skipped and counted in ``degen[kind]``.

Kernels call each other with run numbers, iteration counts and the Jacobi flag wrapped
in ``np.int64``/``np.bool_``: numba compiles a callee once more for every literal value
it is passed (``collision_pass`` was compiled six times), which made up a third of the
first run's compile. The ``project`` flag of the passes stays literal on purpose: its
two versions, residual and projection, each leave out the other's code.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from ._codes import (
    ARC,
    BOX,
    DECAY,
    FACE,
    GROW,
    ITEM,
    K_ACCESS,
    K_BALANCE,
    K_BOUNDARY,
    K_COLLISION,
    K_CURVE,
    K_DISTANCE,
    K_HEAT,
    K_LANE,
    K_ORIENTATION,
    K_STACK,
    K_SYMMETRY,
    K_WALL_DISTANCE,
    K_WALL_ORIENTATION,
    KINDS,
    MAX,
    MIN,
    OBSTACLE,
)

N_KINDS = len(KINDS)
# Empty memo of stiffness_memo: (k0, schedule, k).
NO_MEMO = (-1.0, -1, 0.0)
# The wall flags of nearest_edge when every edge counts (never read then).
NO_WALLS = np.zeros(1, np.bool_)
EPS = 1e-12
# Vertical overlap below which two boxes count as resting on each other, not colliding.
Z_TOUCH_M = 1e-6
# A corner pushed back inside the floor lands this far inside, so it tests as inside.
INSIDE_M = 1e-7

# The photo's frame (frame_item): rounds over its planes per pass, and the share of
# the turn to the narrow side taken per push.
FRAME_ROUNDS = 4
FRAME_TURN = 0.1


# --------------------------------------------------------------------------- helpers


@njit(cache=True, inline="always", error_model="numpy")
def stiffness(k0, schedule, it, rate):
    """k_l for iteration ``it`` >= 1 and rate M (Sec. 3.1)."""
    if schedule == DECAY:
        return 1.0 - (1.0 - k0) ** (rate / it)
    if schedule == GROW:
        return 1.0 - (1.0 - k0) ** (it / rate)
    return k0


@njit(cache=True, inline="always", error_model="numpy")
def stiffness_memo(k0, schedule, it, rate, memo):
    """:func:`stiffness`, remembering the last (k0, schedule, k) of a kernel's loop in
    the tuple ``memo`` (start with NO_MEMO): constraints of one kind nearly always
    share them, and pow is not free. Returns (k, new memo)."""
    if k0 == memo[0] and schedule == memo[1]:
        return memo[2], memo
    k = stiffness(k0, schedule, it, rate)
    return k, (k0, schedule, k)


@njit(cache=True, inline="always", error_model="numpy")
def wrap(a):
    """Angle wrapped to [-pi, pi)."""
    return a - 2.0 * math.pi * math.floor((a + math.pi) / (2.0 * math.pi))


@njit(cache=True, inline="always", error_model="numpy")
def move(b, dx, dy, dz, da, pos, yaw, mstart):
    """Translate body b by (dx, dy, dz) and turn it by da about its center. Returns
    True when b has rigid members: the caller then moves them with :func:`carry`
    and the same numbers, so every world pose stays current.

    (The members' loop is not in here: numba counts references to the arrays on
    every call of an inlined helper that loops or calls, 30 ns a call against 3.)"""
    pos[b, 0] += dx
    pos[b, 1] += dy
    pos[b, 2] += dz
    if da != 0.0:
        yaw[b] += da
    return mstart[b + 1] != mstart[b]


@njit(cache=True, error_model="numpy")
def carry(b, dx, dy, dz, da, pos, yaw, mstart, mlist):
    """Carry the rigid members of body b along after :func:`move` moved it by
    (dx, dy, dz, da)."""
    c = math.cos(da)
    s = math.sin(da)
    for q in range(mstart[b], mstart[b + 1]):
        m = mlist[q]
        rx = pos[m, 0] + dx - pos[b, 0]
        ry = pos[m, 1] + dy - pos[b, 1]
        pos[m, 0] = pos[b, 0] + c * rx - s * ry
        pos[m, 1] = pos[b, 1] + s * rx + c * ry
        pos[m, 2] += dz
        yaw[m] += da


@njit(cache=True, inline="always", error_model="numpy")
def push(b, dx, dy, dz, pos, yaw, acc, jac, mstart):
    """:func:`move` (Gauss–Seidel), or gather the correction for :func:`flush`
    (Jacobi). Returns True when the caller must :func:`carry` members."""
    if jac:
        acc[b, 0] += dx
        acc[b, 1] += dy
        acc[b, 2] += dz
        acc[b, 3] += 1.0
        return False
    return move(b, dx, dy, dz, 0.0, pos, yaw, mstart)


@njit(cache=True, inline="always", error_model="numpy")
def turn(b, da, pos, yaw, acc, jac, mstart):
    """:func:`push` for a turn by da."""
    if jac:
        acc[b, 4] += da
        acc[b, 5] += 1.0
        return False
    return move(b, 0.0, 0.0, 0.0, da, pos, yaw, mstart)


@njit(cache=True, error_model="numpy")
def flush(pos, yaw, acc, omega, mstart, mlist):
    """Apply the averaged Jacobi corrections, Δp = ω/n Σ Δp_j (thesis Eq. 3.6).

    ``acc`` is (n, 6): summed dx, dy, dz, their count, summed dyaw, its count.
    """
    for b in range(pos.shape[0]):
        if acc[b, 3] == 0.0 and acc[b, 5] == 0.0:
            continue
        f = omega / acc[b, 3] if acc[b, 3] > 0.0 else 0.0
        da = omega * acc[b, 4] / acc[b, 5] if acc[b, 5] > 0.0 else 0.0
        if move(b, f * acc[b, 0], f * acc[b, 1], f * acc[b, 2], da, pos, yaw, mstart):
            carry(b, f * acc[b, 0], f * acc[b, 1], f * acc[b, 2], da, pos, yaw, mstart, mlist)
        for q in range(6):
            acc[b, q] = 0.0


@njit(cache=True, inline="always", error_model="numpy")
def batch_end(jac, pos, yaw, acc, omega, P):
    """End of a batch (one constraint kind): Jacobi applies what it gathered."""
    if jac:
        flush(pos, yaw, acc, omega, P.mstart, P.mlist)


@njit(cache=True, error_model="numpy")
def sync_members(P, pos, yaw):
    """Write the world pose of every rigid-group member from its body's pose."""
    for i in range(pos.shape[0]):
        b = P.body[i]
        if b != i:
            c = math.cos(yaw[b])
            s = math.sin(yaw[b])
            ox = P.body_offset[i, 0]
            oy = P.body_offset[i, 1]
            pos[i, 0] = pos[b, 0] + c * ox - s * oy
            pos[i, 1] = pos[b, 1] + s * ox + c * oy
            pos[i, 2] = pos[b, 2] + P.body_offset[i, 2]
            yaw[i] = yaw[b] + P.body_yaw[i]


@njit(cache=True, inline="always", error_model="numpy")
def nearest_edge(poly, walls_only, wall, x, y):
    """Nearest boundary point (qx, qy), its edge (first found on ties; -1 when no edge
    qualifies) and distance, over every edge or, with ``walls_only``, the edges that
    ``wall`` marks."""
    m = poly.shape[0]
    best = 1e300
    bx = 0.0
    by = 0.0
    be = -1
    for e in range(m):
        if walls_only and not wall[e]:
            continue
        ax = poly[e, 0]
        ay = poly[e, 1]
        ex = poly[(e + 1) % m, 0] - ax
        ey = poly[(e + 1) % m, 1] - ay
        ll = ex * ex + ey * ey
        t = ((x - ax) * ex + (y - ay) * ey) / ll if ll > 0.0 else 0.0
        t = min(1.0, max(0.0, t))
        qx = ax + t * ex
        qy = ay + t * ey
        d2 = (x - qx) ** 2 + (y - qy) ** 2
        if d2 < best:
            best = d2
            bx = qx
            by = qy
            be = e
    return bx, by, be, math.sqrt(best)


@njit(cache=True, inline="always", error_model="numpy")
def nearest_on_polygon(poly, x, y):
    """Nearest point on any edge: (qx, qy), its edge and the distance."""
    return nearest_edge(poly, False, NO_WALLS, x, y)


@njit(cache=True, inline="always", error_model="numpy")
def nearest_wall(R, x, y):
    """Nearest point on a wall edge (open edges skipped); the edge is -1 when the room
    has no wall."""
    return nearest_edge(R.polygon, True, R.wall, x, y)


@njit(cache=True, inline="always", error_model="numpy")
def inside_polygon(poly, x, y):
    """Crossing-number point-in-polygon test."""
    m = poly.shape[0]
    inside = False
    j = m - 1
    for i in range(m):
        xi = poly[i, 0]
        yi = poly[i, 1]
        xj = poly[j, 0]
        yj = poly[j, 1]
        if (yi > y) != (yj > y):
            xc = xj + (y - yj) * (xi - xj) / (yi - yj)
            if x < xc:
                inside = not inside
        j = i
    return inside


@njit(cache=True, error_model="numpy")
def points_inside(poly, pts):
    """(k,) bool: :func:`inside_polygon` for each of the (k, 2) points."""
    out = np.empty(pts.shape[0], dtype=np.bool_)
    for k in range(pts.shape[0]):
        out[k] = inside_polygon(poly, pts[k, 0], pts[k, 1])
    return out


@njit(cache=True, error_model="numpy")
def clearance_grid(poly, origin, cell, gx, gy):
    """(gy, gx) grid: for each cell, a distance to the boundary that every point of the
    cell has at least (its center's distance minus the half diagonal), 0 where the
    cell is not entirely inside the polygon."""
    out = np.zeros((gy, gx))
    half_diag = cell * math.sqrt(0.5)
    for r in range(gy):
        y = origin[1] + (r + 0.5) * cell
        for c in range(gx):
            x = origin[0] + (c + 0.5) * cell
            if inside_polygon(poly, x, y):
                _, _, _, d = nearest_on_polygon(poly, x, y)
                out[r, c] = max(0.0, d - half_diag)
    return out


@njit(cache=True, error_model="numpy")
def clear_of_walls(R, x, y, reach):
    """True when the disc of radius ``reach`` around (x, y) certainly lies inside the
    floor (one grid lookup; False means "do the exact test")."""
    c = int(math.floor((x - R.grid_origin[0]) / R.grid_cell[0]))
    r = int(math.floor((y - R.grid_origin[1]) / R.grid_cell[0]))
    if r < 0 or c < 0 or r >= R.clearance.shape[0] or c >= R.clearance.shape[1]:
        return False
    return R.clearance[r, c] > reach


@njit(cache=True, inline="always", error_model="numpy")
def support(hd, hw, c, s, nx, ny):
    """Half-extent along unit direction n of a box with half depth/width and yaw (c, s)."""
    return hd * abs(c * nx + s * ny) + hw * abs(-s * nx + c * ny)


@njit(cache=True, inline="always", error_model="numpy")
def sat(xa, ya, ca, sa, hda, hwa, xb, yb, cb, sb, hdb, hwb):
    """Separating-axis test of two oriented rectangles.

    Returns (depth, nx, ny): the smallest penetration depth (negative = separated by
    that much along the best axis) and the unit axis pointing from b to a.
    """
    dx = xa - xb
    dy = ya - yb
    best = 1e300
    bnx = 1.0
    bny = 0.0
    for k in range(4):
        if k == 0:
            nx, ny = ca, sa
        elif k == 1:
            nx, ny = -sa, ca
        elif k == 2:
            nx, ny = cb, sb
        else:
            nx, ny = -sb, cb
        dist = dx * nx + dy * ny
        depth = support(hda, hwa, ca, sa, nx, ny) + support(hdb, hwb, cb, sb, nx, ny) - abs(dist)
        if depth < best:
            best = depth
            if dist < 0.0:
                bnx, bny = -nx, -ny
            else:
                bnx, bny = nx, ny
    return best, bnx, bny


# ------------------------------------------------------------------- static kinds


@njit(cache=True, error_model="numpy")
def project_distance(D, P, pos, yaw, acc, jac, it, rate, degen):
    """Pairwise (and focal-point) distance, Eqs. (4)–(6); EQ, MIN or MAX."""
    memo = NO_MEMO
    for c in range(D.rest.shape[0]):
        i = D.pairs[c, 0]
        j = D.pairs[c, 1]
        xi, yi = pos[i, 0], pos[i, 1]
        xj, yj = pos[j, 0], pos[j, 1]
        wi = P.inv_mass[P.body[i]] * D.w_scale[c, 0]
        wj = P.inv_mass[P.body[j]] * D.w_scale[c, 1]
        dx = xi - xj
        dy = yi - yj
        length = math.sqrt(dx * dx + dy * dy)
        if wi + wj == 0.0:
            continue
        if length < EPS:
            degen[K_DISTANCE] += 1
            continue
        C = length - D.rest[c]
        if (D.mode[c] == MIN and C >= 0.0) or (D.mode[c] == MAX and C <= 0.0):
            continue
        k, memo = stiffness_memo(D.k0[c], D.schedule[c], it, rate, memo)
        f = k * C / ((wi + wj) * length)
        if push(P.body[i], -wi * f * dx, -wi * f * dy, 0.0, pos, yaw, acc, jac, P.mstart):
            carry(P.body[i], -wi * f * dx, -wi * f * dy, 0.0, 0.0, pos, yaw, P.mstart, P.mlist)
        if push(P.body[j], wj * f * dx, wj * f * dy, 0.0, pos, yaw, acc, jac, P.mstart):
            carry(P.body[j], wj * f * dx, wj * f * dy, 0.0, 0.0, pos, yaw, P.mstart, P.mlist)


@njit(cache=True, error_model="numpy")
def residual_distance(D, P, pos, yaw, out):
    for c in range(D.rest.shape[0]):
        xi, yi = pos[D.pairs[c, 0], 0], pos[D.pairs[c, 0], 1]
        xj, yj = pos[D.pairs[c, 1], 0], pos[D.pairs[c, 1], 1]
        C = math.sqrt((xi - xj) ** 2 + (yi - yj) ** 2) - D.rest[c]
        if D.mode[c] == MIN:
            C = min(C, 0.0)
        elif D.mode[c] == MAX:
            C = max(C, 0.0)
        out[c] = C


@njit(cache=True, inline="always", error_model="numpy")
def lane_geometry(xo, yo, ao, start_x, start_y, angle, length, half_width, xi, yi, ai, wi, di):
    """Ghost point on the lane vector nearest the item, and the required clearance.

    The lane starts at (start_x, start_y) in the frame of the origin (xo, yo, ao) and
    runs ``length`` at ``angle`` from its facing; the item is a box (xi, yi, ai) of
    width ``wi`` and depth ``di``. Returns (C, nx, ny, dist)."""
    co = math.cos(ao)
    so = math.sin(ao)
    sx = xo + co * start_x - so * start_y
    sy = yo + so * start_x + co * start_y
    vx = math.cos(ao + angle)
    vy = math.sin(ao + angle)
    t = min(length, max(0.0, (xi - sx) * vx + (yi - sy) * vy))  # Eq. (8), clamped
    qx = sx + t * vx
    qy = sy + t * vy
    dx = xi - qx
    dy = yi - qy
    dist = math.sqrt(dx * dx + dy * dy)
    if dist < EPS:
        nx, ny = -vy, vx
    else:
        nx, ny = dx / dist, dy / dist
    # Clearance from the item's box, not its center: the half width of the lane plus
    # the item's extent towards the lane.
    need = half_width + support(0.5 * di, 0.5 * wi, math.cos(ai), math.sin(ai), nx, ny)
    return dist - need, nx, ny, dist


@njit(cache=True, error_model="numpy")
def project_lane(L, P, pos, yaw, acc, jac, it, rate, degen):
    """Traffic lane, Eqs. (7)–(8): the item keeps clear of a vector; ghost on origin."""
    memo = NO_MEMO
    for c in range(L.origin.shape[0]):
        i = L.item[c]
        o = L.origin[c]
        C, nx, ny, dist = lane_geometry(
            pos[o, 0], pos[o, 1], yaw[o], L.start[c, 0], L.start[c, 1], L.angle[c], L.length[c], L.half_width[c],
            pos[i, 0], pos[i, 1], yaw[i], P.size[i, 0], P.size[i, 1],
        )
        if C >= 0.0:
            continue
        if dist < EPS:
            degen[K_LANE] += 1
        wi = P.inv_mass[P.body[i]] * L.w_scale[c, 0]
        wo = P.inv_mass[P.body[o]] * L.w_scale[c, 1]
        if wi + wo == 0.0:
            continue
        k, memo = stiffness_memo(L.k0[c], L.schedule[c], it, rate, memo)
        f = k * C / (wi + wo)
        if push(P.body[i], -wi * f * nx, -wi * f * ny, 0.0, pos, yaw, acc, jac, P.mstart):
            carry(P.body[i], -wi * f * nx, -wi * f * ny, 0.0, 0.0, pos, yaw, P.mstart, P.mlist)
        if push(P.body[o], wo * f * nx, wo * f * ny, 0.0, pos, yaw, acc, jac, P.mstart):
            carry(P.body[o], wo * f * nx, wo * f * ny, 0.0, 0.0, pos, yaw, P.mstart, P.mlist)


@njit(cache=True, error_model="numpy")
def residual_lane(L, P, pos, yaw, out):
    for c in range(L.origin.shape[0]):
        i = L.item[c]
        o = L.origin[c]
        C, _, _, _ = lane_geometry(
            pos[o, 0], pos[o, 1], yaw[o], L.start[c, 0], L.start[c, 1], L.angle[c], L.length[c], L.half_width[c],
            pos[i, 0], pos[i, 1], yaw[i], P.size[i, 0], P.size[i, 1],
        )
        out[c] = min(C, 0.0)


@njit(cache=True, inline="always", error_model="numpy")
def weighted_center(P, pos, yaw, members, a, b, by_area):
    """Center of mass of members[a:b] (mass = box volume, or footprint area)."""
    mx = 0.0
    my = 0.0
    total = 0.0
    for q in range(a, b):
        j = members[q]
        mu = P.size[j, 0] * P.size[j, 1] if by_area else P.mass[j]
        x, y = pos[j, 0], pos[j, 1]
        mx += mu * x
        my += mu * y
        total += mu
    return mx / total, my / total, total


@njit(cache=True, inline="always", error_model="numpy")
def project_center(P, pos, yaw, acc, jac, members, a, b, by_area, ex, ey, total, k):
    """Correction of C = ½‖m − p̃‖² (Eqs. 9–10): Δp_j = −k s w_j ∇_j C."""
    denom = 0.0
    for q in range(a, b):
        j = members[q]
        mu = P.size[j, 0] * P.size[j, 1] if by_area else P.mass[j]
        denom += P.inv_mass[P.body[j]] * mu * mu
    if denom == 0.0:
        return
    # s = C / Σ w_j |∇_j C|² with ∇_j C = (μ_j / M) e  =>  Δp_j = −k e w_j μ_j M / (2 Σ w μ²).
    for q in range(a, b):
        j = members[q]
        mu = P.size[j, 0] * P.size[j, 1] if by_area else P.mass[j]
        f = -k * P.inv_mass[P.body[j]] * mu * total / (2.0 * denom)
        if push(P.body[j], f * ex, f * ey, 0.0, pos, yaw, acc, jac, P.mstart):
            carry(P.body[j], f * ex, f * ey, 0.0, 0.0, pos, yaw, P.mstart, P.mlist)


@njit(cache=True, inline="always", error_model="numpy")
def heat_target(H, P, pos, yaw, c):
    fr = H.frame[c]
    if fr < 0:
        return H.target[c, 0], H.target[c, 1]
    x, y, a = pos[fr, 0], pos[fr, 1], yaw[fr]
    ca = math.cos(a)
    sa = math.sin(a)
    return x + ca * H.target[c, 0] - sa * H.target[c, 1], y + sa * H.target[c, 0] + ca * H.target[c, 1]


@njit(cache=True, error_model="numpy")
def project_heat(H, P, pos, yaw, acc, jac, it, rate, degen):
    """Heat point: the members' center of mass goes to a point (Eq. 9)."""
    memo = NO_MEMO
    for c in range(H.frame.shape[0]):
        a = H.start[c]
        b = H.start[c + 1]
        mx, my, total = weighted_center(P, pos, yaw, H.members, a, b, False)
        tx, ty = heat_target(H, P, pos, yaw, c)
        k, memo = stiffness_memo(H.k0[c], H.schedule[c], it, rate, memo)
        project_center(P, pos, yaw, acc, jac, H.members, a, b, False, mx - tx, my - ty, total, k)


@njit(cache=True, error_model="numpy")
def residual_heat(H, P, pos, yaw, out):
    for c in range(H.frame.shape[0]):
        mx, my, _ = weighted_center(P, pos, yaw, H.members, H.start[c], H.start[c + 1], False)
        tx, ty = heat_target(H, P, pos, yaw, c)
        out[c] = 0.5 * ((mx - tx) ** 2 + (my - ty) ** 2)


@njit(cache=True, inline="always", error_model="numpy")
def symmetry_target(S, P, pos, yaw, c, mx, my):
    """Projection of the members' center onto the focal's axis (ray), Eq. (11)."""
    xf, yf, af = pos[S.focal[c], 0], pos[S.focal[c], 1], yaw[S.focal[c]]
    vx = math.cos(af + S.angle[c])
    vy = math.sin(af + S.angle[c])
    t = max(0.0, (mx - xf) * vx + (my - yf) * vy)
    return xf + t * vx, yf + t * vy


@njit(cache=True, error_model="numpy")
def project_symmetry(S, P, pos, yaw, acc, jac, it, rate, degen):
    """Focal point symmetry: members' center of mass onto the focal's axis."""
    memo = NO_MEMO
    for c in range(S.focal.shape[0]):
        a = S.start[c]
        b = S.start[c + 1]
        mx, my, total = weighted_center(P, pos, yaw, S.members, a, b, False)
        tx, ty = symmetry_target(S, P, pos, yaw, c, mx, my)
        k, memo = stiffness_memo(S.k0[c], S.schedule[c], it, rate, memo)
        project_center(P, pos, yaw, acc, jac, S.members, a, b, False, mx - tx, my - ty, total, k)


@njit(cache=True, error_model="numpy")
def residual_symmetry(S, P, pos, yaw, out):
    for c in range(S.focal.shape[0]):
        mx, my, _ = weighted_center(P, pos, yaw, S.members, S.start[c], S.start[c + 1], False)
        tx, ty = symmetry_target(S, P, pos, yaw, c, mx, my)
        out[c] = 0.5 * ((mx - tx) ** 2 + (my - ty) ** 2)


@njit(cache=True, error_model="numpy")
def project_balance(B, P, pos, yaw, acc, jac, it, rate, degen):
    """Visual balance, Eq. (12): footprint-weighted center to the room centroid."""
    memo = NO_MEMO
    for c in range(B.target.shape[0]):
        a = B.start[c]
        b = B.start[c + 1]
        mx, my, total = weighted_center(P, pos, yaw, B.members, a, b, True)
        k, memo = stiffness_memo(B.k0[c], B.schedule[c], it, rate, memo)
        ex = mx - B.target[c, 0]
        ey = my - B.target[c, 1]
        project_center(P, pos, yaw, acc, jac, B.members, a, b, True, ex, ey, total, k)


@njit(cache=True, error_model="numpy")
def residual_balance(B, P, pos, yaw, out):
    for c in range(B.target.shape[0]):
        mx, my, _ = weighted_center(P, pos, yaw, B.members, B.start[c], B.start[c + 1], True)
        out[c] = 0.5 * ((mx - B.target[c, 0]) ** 2 + (my - B.target[c, 1]) ** 2)


@njit(cache=True, inline="always", error_model="numpy")
def wall_frame(R, x, y):
    """Signed distance to the nearest wall (positive inside the floor), the direction
    away from it, and its edge (-1: the room has no wall, and the rest is 0)."""
    qx, qy, e, dist = nearest_wall(R, x, y)
    if e < 0:
        return 0.0, 0.0, 0.0, -1
    if dist < EPS:
        return 0.0, R.edge_normal[e, 0], R.edge_normal[e, 1], e
    nx = (x - qx) / dist
    ny = (y - qy) / dist
    if inside_polygon(R.polygon, x, y):
        return dist, nx, ny, e
    return -dist, -nx, -ny, e


@njit(cache=True, error_model="numpy")
def project_wall_distance(W, R, P, pos, yaw, acc, jac, it, rate, degen):
    """Distance to wall, Eq. (13); the wall point has infinite mass."""
    memo = NO_MEMO
    for c in range(W.item.shape[0]):
        i = W.item[c]
        if P.inv_mass[P.body[i]] == 0.0:
            continue
        x, y = pos[i, 0], pos[i, 1]
        sd, nx, ny, e = wall_frame(R, x, y)
        C = sd - W.rest[c]
        if e < 0 or (W.mode[c] == MIN and C >= 0.0) or (W.mode[c] == MAX and C <= 0.0):
            continue
        k, memo = stiffness_memo(W.k0[c], W.schedule[c], it, rate, memo)
        if push(P.body[i], -k * C * nx, -k * C * ny, 0.0, pos, yaw, acc, jac, P.mstart):
            carry(P.body[i], -k * C * nx, -k * C * ny, 0.0, 0.0, pos, yaw, P.mstart, P.mlist)


@njit(cache=True, error_model="numpy")
def residual_wall_distance(W, R, P, pos, yaw, out):
    for c in range(W.item.shape[0]):
        x, y = pos[W.item[c], 0], pos[W.item[c], 1]
        sd, _, _, e = wall_frame(R, x, y)
        C = 0.0 if e < 0 else sd - W.rest[c]
        if W.mode[c] == MIN:
            C = min(C, 0.0)
        elif W.mode[c] == MAX:
            C = max(C, 0.0)
        out[c] = C


@njit(cache=True, inline="always", error_model="numpy")
def wall_orientation_error(O, R, P, pos, yaw, c):
    x, y, a = pos[O.item[c], 0], pos[O.item[c], 1], yaw[O.item[c]]
    _, _, e, _ = nearest_wall(R, x, y)
    if e < 0:
        return 0.0
    want = math.atan2(R.edge_normal[e, 1], R.edge_normal[e, 0]) + O.angle[c]
    return wrap(want - a)


@njit(cache=True, error_model="numpy")
def project_wall_orientation(O, R, P, pos, yaw, acc, jac, it, rate, degen):
    """Orientation to wall, Eq. (17): smallest rotation towards the wanted angle."""
    memo = NO_MEMO
    for c in range(O.item.shape[0]):
        i = O.item[c]
        if P.inv_mass[P.body[i]] == 0.0:
            continue
        k, memo = stiffness_memo(O.k0[c], O.schedule[c], it, rate, memo)
        da = k * wall_orientation_error(O, R, P, pos, yaw, c)
        if turn(P.body[i], da, pos, yaw, acc, jac, P.mstart):
            carry(P.body[i], 0.0, 0.0, 0.0, da, pos, yaw, P.mstart, P.mlist)


@njit(cache=True, error_model="numpy")
def residual_wall_orientation(O, R, P, pos, yaw, out):
    for c in range(O.item.shape[0]):
        out[c] = abs(wall_orientation_error(O, R, P, pos, yaw, c))


@njit(cache=True, inline="always", error_model="numpy")
def orientation_errors(xi, yi, ai, wi, xj, yj, aj, wj, mode, angle_i, angle_j):
    """Smallest rotations (Δθ_i, Δθ_j) that satisfy a pair's orientation, Eq. (16).

    FACE: i's front points ``angle_i`` off the direction to j (j likewise with
    ``angle_j``; NaN = free). PARALLEL: yaw_i − yaw_j = ``angle_i`` (mod π), the turn
    shared by the inverse masses ``wi`` and ``wj``.
    """
    di = 0.0
    dj = 0.0
    if mode == FACE:
        toward_j = math.atan2(yj - yi, xj - xi)
        if not math.isnan(angle_i):
            di = wrap(angle_i - (ai - toward_j))
        if not math.isnan(angle_j):
            dj = wrap(angle_j - (aj - toward_j - math.pi))
    else:
        err = angle_i - (ai - aj)
        err = (err + 0.5 * math.pi) % math.pi - 0.5 * math.pi
        if wi + wj > 0.0:
            di = err * wi / (wi + wj)
            dj = -err * wj / (wi + wj)
    return di, dj


@njit(cache=True, error_model="numpy")
def orientation_pass(O, P, pos, yaw, acc, jac, it, rate, out, project):
    memo = NO_MEMO
    inv_mass = P.inv_mass
    body = P.body
    for c in range(O.mode.shape[0]):
        i = O.pairs[c, 0]
        j = O.pairs[c, 1]
        wi = inv_mass[body[i]]
        wj = inv_mass[body[j]]
        di, dj = orientation_errors(pos[i, 0], pos[i, 1], yaw[i], wi, pos[j, 0], pos[j, 1], yaw[j], wj,
                                    O.mode[c], O.angle[c, 0], O.angle[c, 1])
        if not project:
            out[c] = math.sqrt(di * di + dj * dj)
            continue
        k, memo = stiffness_memo(O.k0[c], O.schedule[c], it, rate, memo)
        if wi > 0.0:
            if turn(body[i], k * di, pos, yaw, acc, jac, P.mstart):
                carry(body[i], 0.0, 0.0, 0.0, k * di, pos, yaw, P.mstart, P.mlist)
        if wj > 0.0:
            if turn(body[j], k * dj, pos, yaw, acc, jac, P.mstart):
                carry(body[j], 0.0, 0.0, 0.0, k * dj, pos, yaw, P.mstart, P.mlist)


@njit(cache=True, error_model="numpy")
def project_orientation(O, P, pos, yaw, acc, jac, it, rate, degen):
    orientation_pass(O, P, pos, yaw, acc, jac, it, rate, np.empty(0), True)


@njit(cache=True, error_model="numpy")
def residual_orientation(O, P, pos, yaw, out):
    orientation_pass(O, P, pos, yaw, np.empty((0, 6)), np.bool_(False), np.int64(1), 1.0, out, False)


@njit(cache=True, error_model="numpy")
def project_stack(S, P, pos, yaw, acc, jac, it, rate, degen):
    """Vertical stacking, Eqs. (18)–(19). The base rests on what is below it, so only
    the top moves vertically; x and y are shared by inverse mass."""
    memo = NO_MEMO
    for c in range(S.k0.shape[0]):
        i = S.pairs[c, 0]
        j = S.pairs[c, 1]
        xi, yi, zi = pos[i, 0], pos[i, 1], pos[i, 2]
        xj, yj, zj = pos[j, 0], pos[j, 1], pos[j, 2]
        wi = P.inv_mass[P.body[i]]
        wj = P.inv_mass[P.body[j]]
        if wi + wj == 0.0:
            continue
        k, memo = stiffness_memo(S.k0[c], S.schedule[c], it, rate, memo)
        cz = zj - (zi + 0.5 * (P.size[i, 2] + P.size[j, 2]))
        cx = xj - xi
        cy = yj - yi
        fi = k * wi / (wi + wj)
        fj = k * wj / (wi + wj)
        dzj = -k * cz if wj > 0.0 else 0.0
        if push(P.body[i], fi * cx, fi * cy, 0.0, pos, yaw, acc, jac, P.mstart):
            carry(P.body[i], fi * cx, fi * cy, 0.0, 0.0, pos, yaw, P.mstart, P.mlist)
        if push(P.body[j], -fj * cx, -fj * cy, dzj, pos, yaw, acc, jac, P.mstart):
            carry(P.body[j], -fj * cx, -fj * cy, dzj, 0.0, pos, yaw, P.mstart, P.mlist)


@njit(cache=True, error_model="numpy")
def residual_stack(S, P, pos, yaw, out):
    for c in range(S.k0.shape[0]):
        i = S.pairs[c, 0]
        j = S.pairs[c, 1]
        xi, yi, zi = pos[i, 0], pos[i, 1], pos[i, 2]
        xj, yj, zj = pos[j, 0], pos[j, 1], pos[j, 2]
        cz = zj - (zi + 0.5 * (P.size[i, 2] + P.size[j, 2]))
        out[c] = math.sqrt(cz * cz + (xj - xi) ** 2 + (yj - yi) ** 2)


@njit(cache=True, inline="always", error_model="numpy")
def curve_point(kind, p0, p1, p2, p3, p4, lx, ly):
    """Nearest point on a curve (group frame) to (lx, ly), and its parameter in [0, 1].
    ARC: center (p0, p1), radius p2, angles p3 to p4; SEGMENT: (p0, p1) to (p2, p3)."""
    if kind == ARC:
        cx, cy, r, a0, a1 = p0, p1, p2, p3, p4
        phi = math.atan2(ly - cy, lx - cx)
        mid = 0.5 * (a0 + a1)
        phi = mid + wrap(phi - mid)
        phi = min(max(phi, min(a0, a1)), max(a0, a1))
        t = (phi - a0) / (a1 - a0) if a1 != a0 else 0.0
        return cx + r * math.cos(phi), cy + r * math.sin(phi), t
    ax, ay, bx, by = p0, p1, p2, p3
    ex = bx - ax
    ey = by - ay
    ll = ex * ex + ey * ey
    t = ((lx - ax) * ex + (ly - ay) * ey) / ll if ll > 0.0 else 0.0
    t = min(1.0, max(0.0, t))
    return ax + t * ex, ay + t * ey, t


@njit(cache=True, error_model="numpy")
def curve_offsets(U, P, pos, yaw, c, param):
    """For each member of curve c: world offset from its curve point; fills ``param``."""
    g = U.group[c]
    xg, yg, ag = pos[g, 0], pos[g, 1], yaw[g]
    cg = math.cos(ag)
    sg = math.sin(ag)
    a = U.start[c]
    b = U.start[c + 1]
    out = np.empty((b - a, 2))
    kind = U.kind[c]
    p0, p1, p2, p3, p4 = U.params[c, 0], U.params[c, 1], U.params[c, 2], U.params[c, 3], U.params[c, 4]
    for q in range(a, b):
        x, y = pos[U.members[q], 0], pos[U.members[q], 1]
        lx = cg * (x - xg) + sg * (y - yg)
        ly = -sg * (x - xg) + cg * (y - yg)
        px, py, t = curve_point(kind, p0, p1, p2, p3, p4, lx, ly)
        param[q - a] = t
        out[q - a, 0] = x - (xg + cg * px - sg * py)
        out[q - a, 1] = y - (yg + sg * px + cg * py)
    return out


@njit(cache=True, error_model="numpy")
def curve_order(param):
    """Members sorted by curve parameter (insertion sort: nearly sorted each call)."""
    n = param.shape[0]
    order = np.arange(n)
    for a in range(1, n):
        v = order[a]
        b = a - 1
        while b >= 0 and param[order[b]] > param[v]:
            order[b + 1] = order[b]
            b -= 1
        order[b + 1] = v
    return order


@njit(cache=True, error_model="numpy")
def project_curve(U, P, pos, yaw, acc, jac, it, rate, degen):
    """Members of a non-rigid group onto its segment or arc (a distance constraint to
    the nearest curve point, Sec. 3.2), then equal spacing between neighbours in
    curve-parameter order."""
    memo = NO_MEMO
    for c in range(U.group.shape[0]):
        g = U.group[c]
        a = U.start[c]
        b = U.start[c + 1]
        k, memo = stiffness_memo(U.k0[c], U.schedule[c], it, rate, memo)
        wg = 0.0 if U.anchor_fixed[c] else P.inv_mass[P.body[g]]
        param = np.empty(b - a)
        off = curve_offsets(U, P, pos, yaw, c, param)
        for q in range(a, b):
            i = U.members[q]
            wi = P.inv_mass[P.body[i]]
            if wi + wg == 0.0:
                continue
            fi = k * wi / (wi + wg)
            fg = k * wg / (wi + wg)
            dx = off[q - a, 0]
            dy = off[q - a, 1]
            if push(P.body[i], -fi * dx, -fi * dy, 0.0, pos, yaw, acc, jac, P.mstart):
                carry(P.body[i], -fi * dx, -fi * dy, 0.0, 0.0, pos, yaw, P.mstart, P.mlist)
            if fg > 0.0:
                if push(P.body[g], fg * dx, fg * dy, 0.0, pos, yaw, acc, jac, P.mstart):
                    carry(P.body[g], fg * dx, fg * dy, 0.0, 0.0, pos, yaw, P.mstart, P.mlist)
        if U.spacing[c] <= 0.0:
            continue
        order = curve_order(param)
        for q in range(order.shape[0] - 1):
            i = U.members[a + order[q]]
            j = U.members[a + order[q + 1]]
            xi, yi = pos[i, 0], pos[i, 1]
            xj, yj = pos[j, 0], pos[j, 1]
            wi = P.inv_mass[P.body[i]]
            wj = P.inv_mass[P.body[j]]
            dx = xi - xj
            dy = yi - yj
            length = math.sqrt(dx * dx + dy * dy)
            if wi + wj == 0.0:
                continue
            if length < EPS:
                degen[K_CURVE] += 1
                continue
            f = k * (length - U.spacing[c]) / ((wi + wj) * length)
            if push(P.body[i], -wi * f * dx, -wi * f * dy, 0.0, pos, yaw, acc, jac, P.mstart):
                carry(P.body[i], -wi * f * dx, -wi * f * dy, 0.0, 0.0, pos, yaw, P.mstart, P.mlist)
            if push(P.body[j], wj * f * dx, wj * f * dy, 0.0, pos, yaw, acc, jac, P.mstart):
                carry(P.body[j], wj * f * dx, wj * f * dy, 0.0, 0.0, pos, yaw, P.mstart, P.mlist)


@njit(cache=True, error_model="numpy")
def residual_curve(U, P, pos, yaw, out):
    for c in range(U.group.shape[0]):
        a = U.start[c]
        param = np.empty(U.start[c + 1] - a)
        off = curve_offsets(U, P, pos, yaw, c, param)
        total = 0.0
        for q in range(off.shape[0]):
            total += off[q, 0] ** 2 + off[q, 1] ** 2
        if U.spacing[c] > 0.0:
            order = curve_order(param)
            for q in range(order.shape[0] - 1):
                xi, yi = pos[U.members[a + order[q]], 0], pos[U.members[a + order[q]], 1]
                xj, yj = pos[U.members[a + order[q + 1]], 0], pos[U.members[a + order[q + 1]], 1]
                total += (math.sqrt((xi - xj) ** 2 + (yi - yj) ** 2) - U.spacing[c]) ** 2
        out[c] = math.sqrt(total)


# ------------------------------------------------------------ layout boundary


@njit(cache=True, inline="always", error_model="numpy")
def boundary_item(R, P, pos, yaw, i, project):
    """Keep the footprint of item i inside the floor polygon (hard, Sec. 3.3.7).

    Corners outside are moved to the nearest boundary point; reflex (inner) corners of
    the polygon that poke into the box push it out along its axis of least
    penetration, so L- and U-shaped floors are exact. Returns the squared violation
    before projection.
    """
    b = P.body[i]
    hd = 0.5 * P.size[i, 1]
    hw = 0.5 * P.size[i, 0]
    # Quick accept: the footprint's circumcircle lies inside the floor. (Callers first
    # ask the clearance grid, which settles most items without this call.)
    x, y = pos[i, 0], pos[i, 1]
    _, _, _, wall_m = nearest_on_polygon(R.polygon, x, y)
    if wall_m > P.radius[i] and inside_polygon(R.polygon, x, y):
        return 0.0
    violation = 0.0
    for rep in range(4):
        x, y, a = pos[i, 0], pos[i, 1], yaw[i]
        c = math.cos(a)
        s = math.sin(a)
        moved = False
        for k in range(4):
            lx = hd if (k == 1 or k == 2) else -hd
            ly = hw if k >= 2 else -hw
            cx = x + c * lx - s * ly
            cy = y + s * lx + c * ly
            if inside_polygon(R.polygon, cx, cy):
                continue
            qx, qy, e, dist = nearest_on_polygon(R.polygon, cx, cy)
            if rep == 0:
                violation += dist * dist
            if project:
                dx = qx - cx + INSIDE_M * R.edge_normal[e, 0]
                dy = qy - cy + INSIDE_M * R.edge_normal[e, 1]
                if move(b, dx, dy, 0.0, 0.0, pos, yaw, P.mstart):
                    carry(b, dx, dy, 0.0, 0.0, pos, yaw, P.mstart, P.mlist)
                moved = True
                break
        if not project or not moved:
            break
    x, y, a = pos[i, 0], pos[i, 1], yaw[i]
    c = math.cos(a)
    s = math.sin(a)
    for v in range(R.polygon.shape[0]):
        if not R.reflex[v]:
            continue
        dx = R.polygon[v, 0] - x
        dy = R.polygon[v, 1] - y
        lx = c * dx + s * dy
        ly = -s * dx + c * dy
        px = hd - abs(lx)
        py = hw - abs(ly)
        if px <= 0.0 or py <= 0.0:
            continue
        violation += min(px, py) ** 2
        if not project:
            continue
        if px < py:
            sg = -1.0 if lx > 0.0 else 1.0
            if move(b, sg * (px + INSIDE_M) * c, sg * (px + INSIDE_M) * s, 0.0, 0.0, pos, yaw, P.mstart):
                carry(b, sg * (px + INSIDE_M) * c, sg * (px + INSIDE_M) * s, 0.0, 0.0, pos, yaw, P.mstart, P.mlist)
        else:
            sg = -1.0 if ly > 0.0 else 1.0
            if move(b, -sg * (py + INSIDE_M) * s, sg * (py + INSIDE_M) * c, 0.0, 0.0, pos, yaw, P.mstart):
                carry(b, -sg * (py + INSIDE_M) * s, sg * (py + INSIDE_M) * c, 0.0, 0.0, pos, yaw, P.mstart, P.mlist)
        x, y, a = pos[i, 0], pos[i, 1], yaw[i]
    return violation


@njit(cache=True, inline="always", error_model="numpy")
def framed(R, P, i):
    """Whether the photo's frame holds particle i (:func:`frame_item`): a bounded item that
    collides. A rug lies flat: it may run past the photo's edge and into its foreground,
    as rugs do in photos."""
    return P.bounded[i] and P.collides[i] and R.planes.shape[0] > 0


@njit(cache=True, error_model="numpy")
def frame_item(R, P, pos, yaw, i, project):
    """Keep item i's 3-D box inside the space the photo shows (the camera's frustum,
    its lower edge raised to keep the foreground clear): per plane n . p + d >= 0 of
    ``R.planes``, the box's deepest corner (a support function, so exact for boxes) is
    pushed in along the plane's floor direction, and the item turned a little to
    show the plane its narrow side (a wide sofa fits the band a downward photo shows
    only side-on to it). A few rounds, as one plane's push may leave another's.
    Returns the squared violation before projection, in meters."""
    violation = 0.0
    b = P.body[i]
    hw = 0.5 * P.size[i, 0]
    hd = 0.5 * P.size[i, 1]
    hh = 0.5 * P.size[i, 2]
    for rep in range(FRAME_ROUNDS if project else 1):
        moved = False
        for k in range(R.planes.shape[0]):
            nx, ny, nz, d = R.planes[k, 0], R.planes[k, 1], R.planes[k, 2], R.planes[k, 3]
            c = math.cos(yaw[i])
            s = math.sin(yaw[i])
            gap = (nx * pos[i, 0] + ny * pos[i, 1] + nz * pos[i, 2] + d
                   - support(hd, hw, c, s, nx, ny) - hh * abs(nz))
            if gap >= 0.0:
                continue
            if rep == 0:
                violation += gap * gap
            horizontal = nx * nx + ny * ny
            if not project or horizontal <= 1e-9:
                continue
            moved = True
            # The narrow side toward the plane: depth along n when the item is wider than deep.
            along = math.atan2(ny, nx) if hw >= hd else math.atan2(ny, nx) + 0.5 * math.pi
            turn = wrap(along - yaw[i])
            if turn > 0.5 * math.pi:
                turn -= math.pi
            elif turn < -0.5 * math.pi:
                turn += math.pi
            da = FRAME_TURN * turn
            dx = -(gap - INSIDE_M) * nx / horizontal
            dy = -(gap - INSIDE_M) * ny / horizontal
            if move(b, dx, dy, 0.0, da, pos, yaw, P.mstart):
                carry(b, dx, dy, 0.0, da, pos, yaw, P.mstart, P.mlist)
        if not moved:
            break
    return violation


@njit(cache=True, error_model="numpy")
def project_boundary(R, P, pos, yaw):
    """The layout boundary alone, every movable body (:func:`floor_pass`)."""
    floor_pass(R, P, pos, yaw, np.empty((0, 2)), 0.0, body_sides(P, pos, np.int64(1)), np.int64(0), np.bool_(False))


@njit(cache=True, error_model="numpy")
def residual_boundary(R, P, pos, yaw, out):
    for i in range(P.role.shape[0]):
        out[i] = 0.0
        if P.bounded[i] and not clear_of_walls(R, pos[i, 0], pos[i, 1], P.radius[i]):
            out[i] = boundary_item(R, P, pos, yaw, i, False)
        if framed(R, P, i):
            out[i] += frame_item(R, P, pos, yaw, i, False)
        out[i] = -math.sqrt(out[i])


# ------------------------------------------------- collision and accessibility


@njit(cache=True, inline="always", error_model="numpy")
def pair_extent(P, i):
    """Item i's footprint and access boxes as one box in the item's frame: center
    offset (ox, oy) and half depth, half width. The access boxes lie on sides 0/2
    (behind/ahead along the depth axis) and 1/3 (left/right), so the box is
    off-center when only one side needs clearance."""
    a0, a1, a2, a3 = P.access_depth[i, 0], P.access_depth[i, 1], P.access_depth[i, 2], P.access_depth[i, 3]
    return 0.5 * (a2 - a0), 0.5 * (a1 - a3), 0.5 * (P.size[i, 1] + a0 + a2), 0.5 * (P.size[i, 0] + a1 + a3)


@njit(cache=True, inline="always", error_model="numpy")
def pair_box(P, pos, yaw, i, pad_m, box, obb, q):
    """Write row q of ``obb``, item i's :func:`pair_extent` at its pose padded by
    ``pad_m`` (center x, y, cos and sin of the yaw, half depth, half width), and of
    ``box``, the axis-aligned box round it (center x, y, half extent x, y)."""
    ox, oy, hd, hw = pair_extent(P, i)
    c = math.cos(yaw[i])
    s = math.sin(yaw[i])
    x = pos[i, 0] + c * ox - s * oy
    y = pos[i, 1] + s * ox + c * oy
    hd += pad_m
    hw += pad_m
    obb[q, 0], obb[q, 1], obb[q, 2], obb[q, 3], obb[q, 4], obb[q, 5] = x, y, c, s, hd, hw
    box[q, 0], box[q, 1], box[q, 2], box[q, 3] = x, y, abs(c) * hd + abs(s) * hw, abs(s) * hd + abs(c) * hw


@njit(cache=True, inline="always", error_model="numpy")
def obbs_meet(obb, qa, qb):
    """True when the oriented pair boxes qa and qb overlap or touch."""
    depth, _, _ = sat(obb[qa, 0], obb[qa, 1], obb[qa, 2], obb[qa, 3], obb[qa, 4], obb[qa, 5],
                      obb[qb, 0], obb[qb, 1], obb[qb, 2], obb[qb, 3], obb[qb, 4], obb[qb, 5])
    return depth >= 0.0


@njit(cache=True, error_model="numpy")
def pair_grid(P, pos, yaw, cell_m, pad_m, move_m, threads_from):
    """The uniform grid behind the pair list, a Verlet list kept per item.

    Every item that collides or needs clearance, and every obstacle, gets the boxes of
    :func:`pair_box`, padded by ``pad_m``, in the one cell of its center; a pair is
    listed when both its axis-aligned and its oriented boxes meet (the oriented ones
    drop a fifth of the pairs of a crowd of turned boxes), and :func:`refresh_pairs`
    remakes an item's boxes once it has moved by ``move_m``. The list misses no pair
    within ``2 * (pad_m - move_m)`` of meeting. The cell is at least as wide as every
    box at any yaw, so overlapping boxes sit in the same or adjacent cells. Boxes much
    wider than typical (a stage, a door zone) would blow up the cell; they are "big"
    and checked against every box instead.

    Returns the tuple G that :func:`all_pairs` and :func:`refresh_pairs` take: per box
    q its particle ``idx``, its body, whether that body moves, its reach (footprint
    radius plus deepest clearance: how far a turn swings the box), the pose ``ref``
    (x, y, yaw) the boxes were made at, the boxes (m, 4) and (m, 6), the big flags and
    list, each box's cell ``home`` (-1 when big), each cell's boxes as a doubly linked
    list (``head``, ``nxt``, ``prv``), the geometry (x0, y0, cell, nx, ny, pad_m,
    move_m), scratch for the movers (a list of boxes, a flag per particle) and the
    side of every particle's body (:func:`body_sides`), for two threads when there
    are at least ``threads_from`` boxes.

    Pair lists are (k, 3): i < j and the run of the pair (:func:`pair_run`).
    """
    n = P.role.shape[0]
    idx = np.empty(n, np.int64)
    m = 0
    for i in range(n):
        if P.role[i] == OBSTACLE or (P.role[i] == ITEM and (P.collides[i] or P.access_max[i] > 0.0)):
            idx[m] = i
            m += 1
    idx = idx[:m]
    # Looked up once per box here: in the pair loop, through idx, they cost more than
    # the test.
    body = np.empty(m, np.int64)
    movable = np.empty(m, np.bool_)
    reach = np.empty(m)
    ref = np.empty((m, 3))
    box = np.empty((m, 4))
    obb = np.empty((m, 6))
    wide = np.empty(m)
    for q in range(m):
        i = idx[q]
        body[q] = P.body[i]
        movable[q] = P.inv_mass[body[q]] != 0.0
        reach[q] = P.radius[i] + P.access_max[i]
        ref[q, 0] = pos[i, 0]
        ref[q, 1] = pos[i, 1]
        ref[q, 2] = yaw[i]
        pair_box(P, pos, yaw, i, pad_m, box, obb, q)
        _, _, hd, hw = pair_extent(P, i)
        # The box's width at its widest yaw, so a turn never outgrows the cell.
        wide[q] = 2.0 * (math.sqrt(hd * hd + hw * hw) + pad_m)
    cell = cell_m
    x0 = 0.0
    y0 = 0.0
    nx = 1
    ny = 1
    if m > 0:
        big_above = 4.0 * max(np.median(wide), 0.5 * cell_m)
        for q in range(m):
            if wide[q] <= big_above:
                cell = max(cell, wide[q])
        x0 = box[:, 0].min()
        y0 = box[:, 1].min()
        nx = int((box[:, 0].max() - x0) / cell) + 1
        ny = int((box[:, 1].max() - y0) / cell) + 1
        while nx * ny > 4 * m + 64:
            cell *= 1.5
            nx = int((box[:, 0].max() - x0) / cell) + 1
            ny = int((box[:, 1].max() - y0) / cell) + 1
    big = wide > cell
    home = np.full(m, -1, np.int64)
    head = np.full(nx * ny, -1, np.int64)
    nxt = np.full(m, -1, np.int64)
    prv = np.full(m, -1, np.int64)
    geom = np.array([x0, y0, cell, nx, ny, pad_m, move_m], np.float64)
    side = body_sides(P, pos, pair_threads(m, threads_from))
    G = (idx, body, movable, reach, ref, box, obb, big, np.flatnonzero(big), home, head, nxt, prv, geom,
         np.empty(m, np.int64), np.zeros(n, np.bool_), side)
    for q in range(m - 1, -1, -1):
        grid_place(box, big, home, head, nxt, prv, geom, q)
    return G


@njit(cache=True, inline="always", error_model="numpy")
def pair_threads(m, threads_from):
    """Threads for the pair passes of ``m`` boxes: two from ``threads_from`` on."""
    return 2 if m >= threads_from else 1


@njit(cache=True, inline="always", error_model="numpy")
def grid_place(box, big, home, head, nxt, prv, geom, q):
    """Move box q to the cell of its center, clamped to the grid (the grid is sized at
    the start; clamping keeps neighbours neighbours). Big boxes stay out of the grid."""
    if big[q]:
        return
    nx, ny = int(geom[3]), int(geom[4])
    gx = min(nx - 1, max(0, int(math.floor((box[q, 0] - geom[0]) / geom[2]))))
    gy = min(ny - 1, max(0, int(math.floor((box[q, 1] - geom[1]) / geom[2]))))
    g = gy * nx + gx
    if g == home[q]:
        return
    if home[q] >= 0:
        if prv[q] >= 0:
            nxt[prv[q]] = nxt[q]
        else:
            head[home[q]] = nxt[q]
        if nxt[q] >= 0:
            prv[nxt[q]] = prv[q]
    home[q] = g
    prv[q] = -1
    nxt[q] = head[g]
    if head[g] >= 0:
        prv[head[g]] = q
    head[g] = q


@njit(cache=True, inline="always", error_model="numpy")
def boxes_pair(box, obb, body, movable, qa, qb):
    """True when boxes qa and qb overlap, belong to two bodies and one of them moves.
    (Arrays, not the tuple G: unpacking G per call costs more than the test.)"""
    if abs(box[qa, 0] - box[qb, 0]) > box[qa, 2] + box[qb, 2] or abs(box[qa, 1] - box[qb, 1]) > box[qa, 3] + box[qb, 3]:
        return False
    return body[qa] != body[qb] and (movable[qa] or movable[qb]) and obbs_meet(obb, qa, qb)


@njit(cache=True, inline="always", error_model="numpy")
def append_pair(pairs, npairs, i, j, side):
    """Write the pair (min, max) and its run at row ``npairs``, growing the list when
    full."""
    if npairs == pairs.shape[0]:
        pairs = _grown(pairs)
    pairs[npairs, 0] = min(i, j)
    pairs[npairs, 1] = max(i, j)
    pairs[npairs, 2] = pair_run(side[i], side[j])
    return pairs


@njit(cache=True, inline="always", error_model="numpy")
def pair_run(si, sj):
    """Run of a pair for two threads, from the sides of its bodies (-1: fixed): 0 or 1
    when its movable bodies all lie on that side, 2 across. Runs 0 and 1 share no
    movable body, so two threads can project them at the same time, and the result
    does not depend on their timing."""
    if si < 0:
        si = sj
    if sj < 0:
        sj = si
    return si if si == sj and si >= 0 else 2


@njit(cache=True, error_model="numpy")
def all_pairs(G):
    """Every pair (i < j) whose boxes overlap, once: each cell against itself and four
    of its eight neighbours (a half stencil), then the big boxes against all."""
    idx, body, movable, reach, ref, box, obb, big, bigs, home, head, nxt, prv, geom, movers, flag, side = G
    m = box.shape[0]
    nx, ny = int(geom[3]), int(geom[4])
    pairs = np.empty((max(16, 8 * m), 3), np.int64)
    npairs = 0
    # Copies in cell order: the stencil's cells are two runs of consecutive cells, so
    # the inner loop streams through memory.
    start = np.zeros(nx * ny + 1, np.int64)
    for g in range(nx * ny):
        q = head[g]
        count = 0
        while q >= 0:
            count += 1
            q = nxt[q]
        start[g + 1] = start[g] + count
    order = np.empty(start[-1], np.int64)
    for g in range(nx * ny):
        u = start[g]
        q = head[g]
        while q >= 0:
            order[u] = q
            u += 1
            q = nxt[q]
    sx = box[order, 0]
    sy = box[order, 1]
    sex = box[order, 2]
    sey = box[order, 3]
    sidx = idx[order]
    sbody = body[order]
    smovable = movable[order]
    for g in range(nx * ny):
        gx = g % nx
        gy = g // nx
        for u in range(start[g], start[g + 1]):
            xa, ya, exa, eya, ba, ma = sx[u], sy[u], sex[u], sey[u], sbody[u], smovable[u]
            for run in range(2):
                # This cell (later entries) and its east neighbour; then the three
                # cells above.
                if run == 0:
                    first = u + 1
                    last = start[g + 2] if gx + 1 < nx else start[g + 1]
                else:
                    if gy + 1 >= ny:
                        continue
                    first = start[g + nx - 1] if gx > 0 else start[g + nx]
                    last = start[g + nx + 2] if gx + 1 < nx else start[g + nx + 1]
                for v in range(first, last):
                    if abs(xa - sx[v]) > exa + sex[v] or abs(ya - sy[v]) > eya + sey[v]:
                        continue
                    if ba == sbody[v] or not (ma or smovable[v]) or not obbs_meet(obb, order[u], order[v]):
                        continue
                    pairs = append_pair(pairs, npairs, sidx[u], sidx[v], side)
                    npairs += 1
    for qa in bigs:
        for qb in range(m):
            if qb != qa and not (big[qb] and qb < qa) and boxes_pair(box, obb, body, movable, qa, qb):
                pairs = append_pair(pairs, npairs, idx[qa], idx[qb], side)
                npairs += 1
    return pairs[:npairs]


@njit(cache=True, error_model="numpy")
def candidate_pairs(P, pos, yaw, cell_m, pad_m):
    """Pairs (i < j), (k, 2), whose padded boxes (footprint and access boxes, see
    :func:`pair_box`) overlap; the pair list serves the accessibility constraints too."""
    return all_pairs(pair_grid(P, pos, yaw, cell_m, pad_m, 0.0, np.iinfo(np.int64).max))[:, :2].copy()


@njit(cache=True, error_model="numpy")
def refresh_pairs(G, P, pos, yaw, pairs, npairs):
    """Keep the first ``npairs`` of ``pairs`` a valid Verlet list for the current state.

    A pair listed from boxes padded by ``pad_m`` stays valid while neither item has
    moved (or swung, at its reach) by more than ``move_m`` (:func:`pair_grid`) since
    its boxes were made. Only the items that have get new boxes: their pairs are
    dropped and found again in the grid. (Rebuilding the whole list whenever any item had moved that far happened on
    every iteration of a large, crowded floor: something always moves.) Returns the
    list, possibly grown, and its length.
    """
    idx, body, movable, reach, ref, box, obb, big, bigs, home, head, nxt, prv, geom, movers, flag, side = G
    pad_m, move_m = geom[5], geom[6]
    nm = 0
    for q in range(box.shape[0]):
        i = idx[q]
        d = math.sqrt((pos[i, 0] - ref[q, 0]) ** 2 + (pos[i, 1] - ref[q, 1]) ** 2) + reach[q] * abs(yaw[i] - ref[q, 2])
        if d > move_m:
            movers[nm] = q
            nm += 1
            flag[i] = True
            ref[q, 0] = pos[i, 0]
            ref[q, 1] = pos[i, 1]
            ref[q, 2] = yaw[i]
            pair_box(P, pos, yaw, i, pad_m, box, obb, q)
            grid_place(box, big, home, head, nxt, prv, geom, q)
    if nm == 0:
        return pairs, npairs
    keep = 0
    for p in range(npairs):
        if not (flag[pairs[p, 0]] or flag[pairs[p, 1]]):
            pairs[keep, 0] = pairs[p, 0]
            pairs[keep, 1] = pairs[p, 1]
            pairs[keep, 2] = pairs[p, 2]
            keep += 1
    npairs = keep
    nx, ny = int(geom[3]), int(geom[4])
    # Each mover against its cell, all eight neighbours and the big boxes (against
    # every box when it is big itself); a pair of two movers is found by the lower one.
    for t in range(nm):
        qa = movers[t]
        if big[qa]:
            for qb in range(box.shape[0]):
                if qb != qa and boxes_pair(box, obb, body, movable, qa, qb) and not (flag[idx[qb]] and qb < qa):
                    pairs = append_pair(pairs, npairs, idx[qa], idx[qb], side)
                    npairs += 1
            continue
        gx = home[qa] % nx
        gy = home[qa] // nx
        for cy in range(max(0, gy - 1), min(ny, gy + 2)):
            for cx in range(max(0, gx - 1), min(nx, gx + 2)):
                qb = head[cy * nx + cx]
                while qb >= 0:
                    if qb != qa and boxes_pair(box, obb, body, movable, qa, qb) and not (flag[idx[qb]] and qb < qa):
                        pairs = append_pair(pairs, npairs, idx[qa], idx[qb], side)
                        npairs += 1
                    qb = nxt[qb]
        for qb in bigs:
            if boxes_pair(box, obb, body, movable, qa, qb) and not (flag[idx[qb]] and qb < qa):
                pairs = append_pair(pairs, npairs, idx[qa], idx[qb], side)
                npairs += 1
    for t in range(nm):
        flag[idx[movers[t]]] = False
    return pairs, npairs


@njit(cache=True, error_model="numpy")
def _grown(pairs):
    grown = np.empty((max(16, 2 * pairs.shape[0]), pairs.shape[1]), np.int64)
    grown[: pairs.shape[0]] = pairs
    return grown


@njit(cache=True, inline="always", error_model="numpy")
def collision_pair(xi, yi, zi, ci, si, wi, di, hi, ri, xj, yj, zj, cj, sj, wj, dj, hj, rj, model, gap_m):
    """Collision constraint value of a pair (<= 0 when colliding) and its direction.

    Each item is given by its center, (cos, sin) of its yaw, width, depth, height and
    circumradius: scalars, because array arguments to a helper called per pair cost
    more than the test itself in numba. BOX: exact penetration of the oriented
    footprints (SAT), pushed along the axis of least penetration. SPHERE: the paper's
    bounding circles, Eq. (15), activated when the boxes overlap. Returns (C, nx, ny,
    active) with n pointing from j to i.
    """
    if abs(zi - zj) >= 0.5 * (hi + hj) - Z_TOUCH_M:
        return 0.0, 0.0, 0.0, False
    dx = xi - xj
    dy = yi - yj
    if dx * dx + dy * dy >= (ri + rj + gap_m) ** 2:
        return 0.0, 0.0, 0.0, False
    depth, nx, ny = sat(xi, yi, ci, si, 0.5 * di, 0.5 * wi, xj, yj, cj, sj, 0.5 * dj, 0.5 * wj)
    if depth <= -gap_m:
        return 0.0, 0.0, 0.0, False
    if model == BOX:
        return -(depth + gap_m), nx, ny, True
    dist = math.sqrt(dx * dx + dy * dy)
    C = dist - (ri + rj)
    if C >= 0.0:
        return 0.0, 0.0, 0.0, False
    if dist < EPS:
        return C, nx, ny, True
    return C, dx / dist, dy / dist, True


@njit(cache=True, error_model="numpy")
def trig(yaw, cs):
    """(cos, sin) of every yaw; collisions, access and the boundary turn nothing, so
    one table serves a whole phase."""
    for i in range(yaw.shape[0]):
        cs[i, 0] = math.cos(yaw[i])
        cs[i, 1] = math.sin(yaw[i])


@njit(cache=True, error_model="numpy")
def trig_update(yaw, cs, cs_yaw):
    """:func:`trig` for the yaws that differ from ``cs_yaw``, the yaws ``cs`` was made
    from (most items do not turn in an iteration, and sin and cos cost 30 ns)."""
    for i in range(yaw.shape[0]):
        if yaw[i] != cs_yaw[i]:
            cs[i, 0] = math.cos(yaw[i])
            cs[i, 1] = math.sin(yaw[i])
            cs_yaw[i] = yaw[i]


@njit(cache=True, inline="always", error_model="numpy")
def wall_points_pair(P, R, pos, yaw, i, j, model, gap_m):
    """Extra projection between the wall points of two colliding wall-bound items
    (Sec. 3.3.9, Fig. 8b): they slide apart along the wall instead of off it. Door
    and window zones count as wall-bound (they have infinite mass)."""
    xi, yi, ai = pos[i, 0], pos[i, 1], yaw[i]
    xj, yj, aj = pos[j, 0], pos[j, 1], yaw[j]
    qxi, qyi, ei, _ = nearest_wall(R, xi, yi)
    qxj, qyj, ej, _ = nearest_wall(R, xj, yj)
    if ei < 0 or ej < 0:
        return 1.0, 0.0, 0.0, True  # no wall to slide along: nothing to do
    dx = qxi - qxj
    dy = qyi - qyj
    dist = math.sqrt(dx * dx + dy * dy)
    if dist < EPS:
        return 0.0, 0.0, 0.0, False
    tx = dx / dist
    ty = dy / dist
    if model == BOX:
        need = (
            support(0.5 * P.size[i, 1], 0.5 * P.size[i, 0], math.cos(ai), math.sin(ai), tx, ty)
            + support(0.5 * P.size[j, 1], 0.5 * P.size[j, 0], math.cos(aj), math.sin(aj), tx, ty)
            + gap_m
        )
    else:
        need = 0.5 * (
            math.sqrt(P.size[i, 0] ** 2 + P.size[i, 1] ** 2) + math.sqrt(P.size[j, 0] ** 2 + P.size[j, 1] ** 2)
        )
    return dist - need, tx, ty, True


@njit(cache=True, error_model="numpy")
def collision_pass(P, R, pairs, run, pos, yaw, cs, acc, jac, k, model, gap_m, degen, out, project):
    """Every candidate pair once (of ``run`` only, when >= 0: see :func:`pair_run`):
    with ``project``, push colliding pairs apart by ``k`` of their penetration
    (Gauss–Seidel or Jacobi); without, write each pair's C (0 when apart) to ``out``.
    Returns the number of colliding pairs."""
    size = P.size
    radius = P.radius
    collides = P.collides
    colliding = 0
    for p in range(pairs.shape[0]):
        if run >= 0 and pairs[p, 2] != run:
            continue
        i = pairs[p, 0]
        j = pairs[p, 1]
        if not project:
            out[p] = 0.0
        if not (collides[i] and collides[j]):
            continue
        C, nx, ny, active = collision_pair(
            pos[i, 0], pos[i, 1], pos[i, 2], cs[i, 0], cs[i, 1], size[i, 0], size[i, 1], size[i, 2], radius[i],
            pos[j, 0], pos[j, 1], pos[j, 2], cs[j, 0], cs[j, 1], size[j, 0], size[j, 1], size[j, 2], radius[j],
            model, gap_m,
        )
        if not active:
            continue
        colliding += 1
        if not project:
            out[p] = C
            continue
        wi = P.inv_mass[P.body[i]]
        wj = P.inv_mass[P.body[j]]
        f = k * C / (wi + wj)
        # A fixed body is never written, not even with a zero: two threads may share it.
        if wi > 0.0:
            if push(P.body[i], -wi * f * nx, -wi * f * ny, 0.0, pos, yaw, acc, jac, P.mstart):
                carry(P.body[i], -wi * f * nx, -wi * f * ny, 0.0, 0.0, pos, yaw, P.mstart, P.mlist)
        if wj > 0.0:
            if push(P.body[j], wj * f * nx, wj * f * ny, 0.0, pos, yaw, acc, jac, P.mstart):
                carry(P.body[j], wj * f * nx, wj * f * ny, 0.0, 0.0, pos, yaw, P.mstart, P.mlist)
        # Door and window zones sit on a wall too: a wall-bound item slides past them.
        if (P.wall_bound[i] or P.role[i] == OBSTACLE) and (P.wall_bound[j] or P.role[j] == OBSTACLE):
            C2, tx, ty, ok = wall_points_pair(P, R, pos, yaw, i, j, model, gap_m)
            if not ok:
                degen[K_COLLISION] += 1
            elif C2 < 0.0:
                f = k * C2 / (wi + wj)
                if wi > 0.0:
                    if push(P.body[i], -wi * f * tx, -wi * f * ty, 0.0, pos, yaw, acc, jac, P.mstart):
                        carry(P.body[i], -wi * f * tx, -wi * f * ty, 0.0, 0.0, pos, yaw, P.mstart, P.mlist)
                if wj > 0.0:
                    if push(P.body[j], wj * f * tx, wj * f * ty, 0.0, pos, yaw, acc, jac, P.mstart):
                        carry(P.body[j], wj * f * tx, wj * f * ty, 0.0, 0.0, pos, yaw, P.mstart, P.mlist)
    return colliding


@njit(cache=True, error_model="numpy")
def project_collision(P, R, pairs, pos, yaw, cs, acc, jac, k, model, gap_m, degen):
    return collision_pass(P, R, pairs, np.int64(-1), pos, yaw, cs, acc, jac, k, model, gap_m, degen, np.empty(0), True)


@njit(cache=True, error_model="numpy")
def residual_collision(P, R, pairs, pos, cs, model, out):
    # The projection-only arguments are placeholders here.
    return collision_pass(P, R, pairs, np.int64(-1), pos, np.empty(0), cs, np.empty((0, 6)), np.bool_(False), 0.0,
                          model, 0.0, np.zeros(N_KINDS, np.int64), out, False)


@njit(cache=True, inline="always", error_model="numpy")
def access_side(xo, yo, co, so, wo, do, depth_m, side, xi, yi, ci, si, wi, di, model):
    """Accessibility of side ``side`` of an owner against another item (Eq. 14).

    Both boxes come as scalars (center, cos/sin of yaw, width, depth; ``depth_m`` is
    the clearance of that side). Active only when the other item's box intersects the
    access box. BOX: exact penetration into the access box; SPHERE: the paper's
    ‖p_i − a_jk‖ − (b_i + ad_jk) with b and ad the half diagonals. Returns (C, nx, ny,
    active), n from the access box to the other item.
    """
    hd = 0.5 * do
    hw = 0.5 * wo
    if side == 0 or side == 2:
        sgn = 1.0 if side == 2 else -1.0
        lx = sgn * (hd + 0.5 * depth_m)
        ly = 0.0
        bhd = 0.5 * depth_m
        bhw = hw
    else:
        sgn = 1.0 if side == 1 else -1.0
        lx = 0.0
        ly = sgn * (hw + 0.5 * depth_m)
        bhd = hd
        bhw = 0.5 * depth_m
    ax = xo + co * lx - so * ly
    ay = yo + so * lx + co * ly
    hdi = 0.5 * di
    hwi = 0.5 * wi
    reach = math.sqrt(hdi * hdi + hwi * hwi) + math.sqrt(bhd * bhd + bhw * bhw)
    if (xi - ax) ** 2 + (yi - ay) ** 2 >= reach * reach:
        return 0.0, 0.0, 0.0, False
    depth, nx, ny = sat(xi, yi, ci, si, hdi, hwi, ax, ay, co, so, bhd, bhw)
    if depth <= 0.0:
        return 0.0, 0.0, 0.0, False
    if model == BOX:
        return -depth, nx, ny, True
    dx = xi - ax
    dy = yi - ay
    dist = math.sqrt(dx * dx + dy * dy)
    C = dist - reach
    if C >= 0.0:
        return 0.0, 0.0, 0.0, False
    if dist < EPS:
        return C, nx, ny, True
    return C, dx / dist, dy / dist, True


@njit(cache=True, error_model="numpy")
def access_pass(P, pairs, run, pos, yaw, cs, acc, jac, k, model, out, project):
    """Accessibility of both items of every candidate pair: with ``project``, push the
    intruder out of each access box it enters by ``k`` of the depth (the owner takes
    its share by mass); without, write each pair's -sqrt(Σ C²) to ``out``.

    Members of one group (a table and its chairs) may sit in each other's access.
    """
    size = P.size
    radius = P.radius
    depth = P.access_depth
    # Local circles, because a Gauss–Seidel pass moves items while it runs (but never
    # turns them).
    zone = P.access_zone
    for p in range(pairs.shape[0]):
        if run >= 0 and pairs[p, 2] != run:
            continue
        total = 0.0
        for turn_ in range(2):
            owner = pairs[p, turn_]
            other = pairs[p, 1 - turn_]
            # Most pairs are rejected here, by the circle around the owner's access boxes.
            if zone[owner, 2] < 0.0:
                continue
            zx = pos[owner, 0] + cs[owner, 0] * zone[owner, 0] - cs[owner, 1] * zone[owner, 1]
            zy = pos[owner, 1] + cs[owner, 1] * zone[owner, 0] + cs[owner, 0] * zone[owner, 1]
            reach = zone[owner, 2] + radius[other]
            if (zx - pos[other, 0]) ** 2 + (zy - pos[other, 1]) ** 2 >= reach * reach:
                continue
            if P.role[owner] != ITEM or P.role[other] != ITEM or not P.collides[other]:
                continue
            if P.parent[owner] >= 0 and P.parent[owner] == P.parent[other]:
                continue
            if abs(pos[owner, 2] - pos[other, 2]) >= 0.5 * (size[owner, 2] + size[other, 2]) - Z_TOUCH_M:
                continue
            wo = P.inv_mass[P.body[owner]]
            wi = P.inv_mass[P.body[other]]
            if project and wo + wi == 0.0:
                continue
            for side in range(4):
                if depth[owner, side] <= 0.0:
                    continue
                C, nx, ny, active = access_side(
                    pos[owner, 0], pos[owner, 1], cs[owner, 0], cs[owner, 1], size[owner, 0], size[owner, 1],
                    depth[owner, side], side,
                    pos[other, 0], pos[other, 1], cs[other, 0], cs[other, 1], size[other, 0], size[other, 1], model,
                )
                if not active:
                    continue
                if not project:
                    total += C * C
                    continue
                f = k * C / (wo + wi)
                if wi > 0.0:
                    if push(P.body[other], -wi * f * nx, -wi * f * ny, 0.0, pos, yaw, acc, jac, P.mstart):
                        carry(P.body[other], -wi * f * nx, -wi * f * ny, 0.0, 0.0, pos, yaw, P.mstart, P.mlist)
                if wo > 0.0:
                    if push(P.body[owner], wo * f * nx, wo * f * ny, 0.0, pos, yaw, acc, jac, P.mstart):
                        carry(P.body[owner], wo * f * nx, wo * f * ny, 0.0, 0.0, pos, yaw, P.mstart, P.mlist)
        if not project:
            out[p] = -math.sqrt(total)


@njit(cache=True, error_model="numpy")
def project_access(P, pairs, pos, yaw, cs, acc, jac, k, model, degen):
    access_pass(P, pairs, np.int64(-1), pos, yaw, cs, acc, jac, k, model, np.empty(0), True)


@njit(cache=True, inline="always", error_model="numpy")
def access_in_floor(R, P, pos, yaw, cs, i, k, project):
    """Clearances must lie on the floor too (beyond the paper): an access box whose
    outer corners leave the floor pulls its item back by ``k`` of the excess, so a
    trash can does not end up facing a wall. Returns the squared excess."""
    excess = 0.0
    hd = 0.5 * P.size[i, 1]
    hw = 0.5 * P.size[i, 0]
    # Quick accept: every clearance lies within this circle, itself inside the floor.
    # (Callers first ask the clearance grid, which settles most items without this call.)
    _, _, _, wall_m = nearest_on_polygon(R.polygon, pos[i, 0], pos[i, 1])
    if wall_m > P.radius[i] + P.access_max[i] and inside_polygon(R.polygon, pos[i, 0], pos[i, 1]):
        return 0.0
    for side in range(4):
        depth = P.access_depth[i, side]
        if depth <= 0.0:
            continue
        for end in range(2):
            sgn = 1.0 if end == 0 else -1.0
            if side == 0:
                lx, ly = -hd - depth, sgn * hw
            elif side == 2:
                lx, ly = hd + depth, sgn * hw
            elif side == 1:
                lx, ly = sgn * hd, hw + depth
            else:
                lx, ly = sgn * hd, -hw - depth
            c = cs[i, 0]
            s = cs[i, 1]
            x = pos[i, 0] + c * lx - s * ly
            y = pos[i, 1] + s * lx + c * ly
            if inside_polygon(R.polygon, x, y):
                continue
            qx, qy, _, dist = nearest_on_polygon(R.polygon, x, y)
            excess += dist * dist
            if project:
                if move(P.body[i], k * (qx - x), k * (qy - y), 0.0, 0.0, pos, yaw, P.mstart):
                    carry(P.body[i], k * (qx - x), k * (qy - y), 0.0, 0.0, pos, yaw, P.mstart, P.mlist)
    return excess


@njit(cache=True, error_model="numpy")
def residual_access_in_floor(R, P, pos, yaw, cs):
    total = 0.0
    for i in range(P.role.shape[0]):
        if P.role[i] == ITEM and P.access_max[i] > 0.0:
            if not clear_of_walls(R, pos[i, 0], pos[i, 1], P.radius[i] + P.access_max[i]):
                total += access_in_floor(R, P, pos, yaw, cs, i, 0.0, False)
    return total


@njit(cache=True, error_model="numpy")
def residual_access(P, pairs, pos, cs, model, out):
    """Squared-sum violation of all access sides, per candidate pair."""
    access_pass(P, pairs, np.int64(-1), pos, np.empty(0), cs, np.empty((0, 6)), np.bool_(False), 0.0, model, out, False)


# ------------------------------------------- two threads for the pair passes


@njit(cache=True, error_model="numpy")
def body_sides(P, pos, threads):
    """The side of every particle's body for :func:`pair_run`, -1 where the body is
    fixed. With two ``threads``, 0 or 1 split at the median x of the movable bodies;
    with one, 0 for all."""
    n = pos.shape[0]
    xs = np.empty(n)
    k = 0
    for b in range(n):
        if P.body[b] == b and P.inv_mass[b] != 0.0:
            xs[k] = pos[b, 0]
            k += 1
    cut = np.median(xs[:k]) if k > 0 and threads > 1 else np.inf
    side = np.full(n, -1, np.int8)
    for i in range(n):
        b = P.body[i]
        if P.inv_mass[b] != 0.0:
            side[i] = 1 if pos[b, 0] >= cut else 0
    return side


@njit(cache=True, parallel=True, error_model="numpy")
def project_collision_split(P, R, pairs, pos, yaw, cs, acc, jac, k, model, gap_m, degen):
    """:func:`project_collision` over the runs of :func:`pair_run`: runs 0 and 1 on
    two threads, then the pairs across."""
    local = np.zeros((2, N_KINDS), np.int64)
    for t in prange(2):
        collision_pass(P, R, pairs, np.int64(t), pos, yaw, cs, acc, jac, k, model, gap_m, local[t], np.empty(0), True)
    collision_pass(P, R, pairs, np.int64(2), pos, yaw, cs, acc, jac, k, model, gap_m, degen, np.empty(0), True)
    for q in range(N_KINDS):
        degen[q] += local[0, q] + local[1, q]


@njit(cache=True, parallel=True, error_model="numpy")
def project_access_split(P, pairs, pos, yaw, cs, acc, jac, k, model):
    """:func:`project_access` over the runs of :func:`pair_run`, like
    :func:`project_collision_split`."""
    for t in prange(2):
        access_pass(P, pairs, np.int64(t), pos, yaw, cs, acc, jac, k, model, np.empty(0), True)
    access_pass(P, pairs, np.int64(2), pos, yaw, cs, acc, jac, k, model, np.empty(0), True)


@njit(cache=True, error_model="numpy")
def floor_pass(R, P, pos, yaw, cs, k_access, side, t, access):
    """The clearances on the floor (with ``access``), then the layout boundary (the
    photo's frame, then the floor), for the particles whose body lies on side ``t``
    (:func:`body_sides`)."""
    if access:
        for i in range(P.role.shape[0]):
            if side[i] == t and P.role[i] == ITEM and P.access_max[i] > 0.0:
                if not clear_of_walls(R, pos[i, 0], pos[i, 1], P.radius[i] + P.access_max[i]):
                    access_in_floor(R, P, pos, yaw, cs, i, k_access, True)
    for i in range(P.role.shape[0]):
        if side[i] == t and framed(R, P, i):
            frame_item(R, P, pos, yaw, i, True)
        if side[i] == t and P.bounded[i] and not clear_of_walls(R, pos[i, 0], pos[i, 1], P.radius[i]):
            boundary_item(R, P, pos, yaw, i, True)


@njit(cache=True, parallel=True, error_model="numpy")
def project_floor_split(R, P, pos, yaw, cs, k_access, side, access):
    """:func:`floor_pass` for both sides, each on its own thread: a thread moves only
    its own bodies, so the boundary still comes last for each."""
    for t in prange(2):
        floor_pass(R, P, pos, yaw, cs, k_access, side, np.int64(t), access)


@njit(cache=True, parallel=True, error_model="numpy")
def pair_residuals(P, R, pairs, pos, cs, model, out_collision, out_access):
    """Collision and access residuals of every pair, the list cut in two halves for
    two threads (each writes its own entries, so the sums stay exact)."""
    half = pairs.shape[0] // 2
    for t in prange(2):
        lo = 0 if t == 0 else half
        hi = half if t == 0 else pairs.shape[0]
        residual_collision(P, R, pairs[lo:hi], pos, cs, model, out_collision[lo:hi])
        residual_access(P, pairs[lo:hi], pos, cs, model, out_access[lo:hi])


# ------------------------------------------------------------------ energy, loop


@njit(cache=True, error_model="numpy")
def sumsq(values, n):
    total = 0.0
    for i in range(n):
        total += values[i] * values[i]
    return total


@njit(cache=True, error_model="numpy")
def energy_terms(M, pos, yaw, cs, pairs, model, weights):
    """Weighted squared residual of each kind, Σ_j g_j C_j² (Eq. 1, before the root);
    ``cs`` holds (cos, sin) of every yaw (:func:`trig`)."""
    R = M[11]
    collision = np.empty(pairs.shape[0])
    access = np.empty(pairs.shape[0])
    residual_collision(M[0], R, pairs, pos, cs, model, collision)
    residual_access(M[0], pairs, pos, cs, model, access)
    return kind_terms(M, pos, yaw, cs, collision, access, weights)


@njit(cache=True, error_model="numpy")
def kind_terms(M, pos, yaw, cs, collision, access, weights):
    """:func:`energy_terms` from the residuals of the pairs, ``collision`` and
    ``access`` (:func:`residual_collision` and :func:`residual_access`, or
    :func:`pair_residuals` on two threads: kept out of :func:`energy_terms`, which the
    annealer in another module calls, because numba's disk cache does not notice
    when a parallel kernel of another module changes)."""
    P, D, L, H, S, B, W, WO, O, ST, U, R = M
    terms = np.zeros(N_KINDS)
    out = np.empty(max(P.role.shape[0], D.rest.shape[0], L.origin.shape[0],
                       H.frame.shape[0], S.focal.shape[0], B.target.shape[0], W.item.shape[0],
                       WO.item.shape[0], O.mode.shape[0], ST.k0.shape[0], U.group.shape[0], 1))
    if D.rest.shape[0] > 0:
        residual_distance(D, P, pos, yaw, out)
        terms[K_DISTANCE] = sumsq(out, D.rest.shape[0])
    if L.origin.shape[0] > 0:
        residual_lane(L, P, pos, yaw, out)
        terms[K_LANE] = sumsq(out, L.origin.shape[0])
    if H.frame.shape[0] > 0:
        residual_heat(H, P, pos, yaw, out)
        terms[K_HEAT] = sumsq(out, H.frame.shape[0])
    if S.focal.shape[0] > 0:
        residual_symmetry(S, P, pos, yaw, out)
        terms[K_SYMMETRY] = sumsq(out, S.focal.shape[0])
    if B.target.shape[0] > 0:
        residual_balance(B, P, pos, yaw, out)
        terms[K_BALANCE] = sumsq(out, B.target.shape[0])
    if W.item.shape[0] > 0:
        residual_wall_distance(W, R, P, pos, yaw, out)
        terms[K_WALL_DISTANCE] = sumsq(out, W.item.shape[0])
    if WO.item.shape[0] > 0:
        residual_wall_orientation(WO, R, P, pos, yaw, out)
        terms[K_WALL_ORIENTATION] = sumsq(out, WO.item.shape[0])
    if O.mode.shape[0] > 0:
        residual_orientation(O, P, pos, yaw, out)
        terms[K_ORIENTATION] = sumsq(out, O.mode.shape[0])
    if ST.k0.shape[0] > 0:
        residual_stack(ST, P, pos, yaw, out)
        terms[K_STACK] = sumsq(out, ST.k0.shape[0])
    if U.group.shape[0] > 0:
        residual_curve(U, P, pos, yaw, out)
        terms[K_CURVE] = sumsq(out, U.group.shape[0])
    residual_boundary(R, P, pos, yaw, out)
    terms[K_BOUNDARY] = sumsq(out, P.role.shape[0])
    terms[K_COLLISION] = sumsq(collision, collision.shape[0])
    terms[K_ACCESS] = sumsq(access, access.shape[0]) + residual_access_in_floor(R, P, pos, yaw, cs)
    for k in range(N_KINDS):
        terms[k] *= weights[k]
    return terms


@njit(cache=True, error_model="numpy")
def iterate(M, pos, yaw, pairs, side, threads, acc, cs, cs_yaw, degen, it, rate, jac, omega, order, model,
            k_collision, k_access, gap_m):
    """One solver iteration ``it`` (1-based): the constraints of its row of the
    interleaving table, then stacking, collision, accessibility and the boundary.
    With two ``threads``, the pairs' runs (:func:`pair_run`) come from ``side``;
    ``cs`` is kept current with :func:`trig_update`.
    Kinds without constraints are skipped: a kernel call costs a few hundred
    nanoseconds of argument passing, which adds up in a ten-item room."""
    P, D, L, H, S, B, W, WO, O, ST, U, R = M
    row = (it - 1) % 6
    others = order[row, 1]
    if others:
        if D.rest.shape[0] > 0:
            project_distance(D, P, pos, yaw, acc, jac, it, rate, degen)
            batch_end(jac, pos, yaw, acc, omega, P)
        if L.origin.shape[0] > 0:
            project_lane(L, P, pos, yaw, acc, jac, it, rate, degen)
            batch_end(jac, pos, yaw, acc, omega, P)
        if H.frame.shape[0] > 0:
            project_heat(H, P, pos, yaw, acc, jac, it, rate, degen)
            batch_end(jac, pos, yaw, acc, omega, P)
        if S.focal.shape[0] > 0:
            project_symmetry(S, P, pos, yaw, acc, jac, it, rate, degen)
            batch_end(jac, pos, yaw, acc, omega, P)
        if B.target.shape[0] > 0:
            project_balance(B, P, pos, yaw, acc, jac, it, rate, degen)
            batch_end(jac, pos, yaw, acc, omega, P)
        if O.mode.shape[0] > 0:
            project_orientation(O, P, pos, yaw, acc, jac, it, rate, degen)
            batch_end(jac, pos, yaw, acc, omega, P)
        if U.group.shape[0] > 0:
            project_curve(U, P, pos, yaw, acc, jac, it, rate, degen)
            batch_end(jac, pos, yaw, acc, omega, P)
    if order[row, 0]:
        if W.item.shape[0] > 0:
            project_wall_distance(W, R, P, pos, yaw, acc, jac, it, rate, degen)
            batch_end(jac, pos, yaw, acc, omega, P)
        if WO.item.shape[0] > 0:
            project_wall_orientation(WO, R, P, pos, yaw, acc, jac, it, rate, degen)
            batch_end(jac, pos, yaw, acc, omega, P)
    if ST.k0.shape[0] > 0:
        project_stack(ST, P, pos, yaw, acc, jac, it, rate, degen)
        batch_end(jac, pos, yaw, acc, omega, P)
    if order[row, 2]:
        trig_update(yaw, cs, cs_yaw)
        kc = stiffness(k_collision, GROW, it, rate)
        if threads > 1:
            project_collision_split(P, R, pairs, pos, yaw, cs, acc, jac, kc, model, gap_m, degen)
        else:
            project_collision(P, R, pairs, pos, yaw, cs, acc, jac, kc, model, gap_m, degen)
        batch_end(jac, pos, yaw, acc, omega, P)
        if threads > 1:
            project_access_split(P, pairs, pos, yaw, cs, acc, jac, k_access, model)
        else:
            project_access(P, pairs, pos, yaw, cs, acc, jac, k_access, model, degen)
        batch_end(jac, pos, yaw, acc, omega, P)
    if threads > 1:
        project_floor_split(R, P, pos, yaw, cs, k_access, side, order[row, 2])
    else:
        floor_pass(R, P, pos, yaw, cs, k_access, side, np.int64(0), order[row, 2])


@njit(cache=True, error_model="numpy")
def polish(M, pos, yaw, rounds, model, gap_m, cell_m, pad_m):
    """Hard constraints only, at full stiffness: collisions and the boundary, until no
    pair collides (beyond the paper: the best layout seen may keep millimetre
    overlaps that the quadratic energy barely notices)."""
    P, D, L, H, S, B, W, WO, O, ST, U, R = M
    n = pos.shape[0]
    acc = np.zeros((n, 6))
    cs = np.empty((n, 2))
    degen = np.zeros(N_KINDS, np.int64)
    for _ in range(rounds):
        pairs = candidate_pairs(P, pos, yaw, cell_m, pad_m)
        trig(yaw, cs)
        if residual_collision(P, R, pairs, pos, cs, model, np.empty(pairs.shape[0])) == 0:
            return
        project_collision(P, R, pairs, pos, yaw, cs, acc, np.bool_(False), 1.0, model, gap_m, degen)
        project_stack(ST, P, pos, yaw, acc, np.bool_(False), np.int64(1), 1.0, degen)
        project_boundary(R, P, pos, yaw)


@njit(cache=True, error_model="numpy")
def solve_loop(M, pos, yaw, max_iter, min_iter, patience, tol, atol, rate, jac, omega, order, model, k_collision,
               k_access, gap_m, cell_m, pad_m, weights, energy_every, polish_rounds, threads_from):
    """Algorithm 1: project all constraints per iteration, keep the best layout.

    Per iteration ``it`` (1-based) the interleaving row ``order[(it - 1) % 6]`` says
    whether the soft ("others") and wall constraints are projected (thesis Table 5.1);
    stacking, collision, accessibility and the layout boundary are projected every
    iteration, the boundary last so every layout handed out is inside the floor.

    The loop stops after ``max_iter`` iterations, or (not before ``min_iter``) once
    the best energy has not improved by more than the fraction ``tol`` plus ``atol``
    for ``patience`` iterations.

    The best layout is then polished (:func:`polish`, ``polish_rounds`` at most) and
    the polished one kept if it collides less.

    The pair list is a Verlet list kept per item (:func:`refresh_pairs`). From
    ``threads_from`` boxes on, the pair passes, the floor pass and the pairs' energy
    run on two threads (:func:`pair_run`): the result depends on that choice, never
    on the threads' timing.

    Returns the best positions and yaws, the energy trace (trace[l] = energy before
    iteration l + 1), the best iteration, the iterations run and degenerate counts.
    """
    P, D, L, H, S, B, W, WO, O, ST, U, R = M
    n = pos.shape[0]
    acc = np.zeros((n, 6))
    cs = np.empty((n, 2))
    degen = np.zeros(N_KINDS, np.int64)
    trace = np.full(max_iter + 1, np.nan)
    best_pos = pos.copy()
    best_yaw = yaw.copy()
    best_e = np.inf
    best_terms = np.zeros(N_KINDS)
    best_it = 0
    ref_e = np.inf
    ref_it = 0
    it = 0
    trig(yaw, cs)
    cs_yaw = yaw.copy()
    # Boxes padded by half the slack and remade after half: two items must close in
    # by pad_m before a pair within the collision gap could be missed.
    G = pair_grid(P, pos, yaw, cell_m, 0.5 * pad_m + gap_m, 0.5 * pad_m, threads_from)
    threads = pair_threads(G[0].shape[0], threads_from)
    side = G[-1]
    pairs = all_pairs(G)
    npairs = pairs.shape[0]
    rc = np.empty(0)
    ra = np.empty(0)
    while True:
        pairs, npairs = refresh_pairs(G, P, pos, yaw, pairs, npairs)
        live = pairs[:npairs]
        if it % energy_every == 0 or it >= max_iter:
            trig_update(yaw, cs, cs_yaw)
            if threads > 1:
                if rc.shape[0] < npairs:
                    rc = np.empty(pairs.shape[0])
                    ra = np.empty(pairs.shape[0])
                pair_residuals(P, R, live, pos, cs, model, rc[:npairs], ra[:npairs])
                terms = kind_terms(M, pos, yaw, cs, rc[:npairs], ra[:npairs], weights)
            else:
                terms = energy_terms(M, pos, yaw, cs, live, model, weights)
            e = math.sqrt(terms.sum())
            trace[it] = e
            if e < best_e:
                best_e = e
                best_terms[:] = terms
                best_it = it
                best_pos[:] = pos
                best_yaw[:] = yaw
            if e < ref_e * (1.0 - tol) - atol:
                ref_e = e
                ref_it = it
            if it >= max_iter or (it >= min_iter and it - ref_it >= patience):
                break
        else:
            trace[it] = trace[it - 1]
        it += 1
        iterate(M, pos, yaw, live, side, threads, acc, cs, cs_yaw, degen, it, rate, jac, omega, order,
                model, k_collision, k_access, gap_m)
    if polish_rounds > 0:
        pos[:] = best_pos
        yaw[:] = best_yaw
        polish(M, pos, yaw, polish_rounds, model, gap_m, cell_m, pad_m)
        pairs = candidate_pairs(P, pos, yaw, cell_m, pad_m)
        trig(yaw, cs)
        # Keep the polished layout when it collides less (hard constraints first).
        terms = energy_terms(M, pos, yaw, cs, pairs, model, weights)
        hard_after = terms[K_COLLISION] + terms[K_BOUNDARY]
        hard_before = best_terms[K_COLLISION] + best_terms[K_BOUNDARY]
        if hard_after < hard_before or (hard_after == hard_before and terms.sum() <= best_terms.sum()):
            best_pos[:] = pos
            best_yaw[:] = yaw
    return best_pos, best_yaw, trace[: it + 1], best_it, it, degen


@njit(cache=True, error_model="numpy")
def ray_box_entry(origin, dirs, pos, yaw, size, out):
    """Entry distance of each ray (from ``origin`` along ``dirs (r, 3)``) into each turned box
    (``pos (n, 3)`` centres, ``yaw (n,)``, ``size (n, 3)`` width, depth, height) into
    ``out (r, n)``: 0 for a ray starting inside, inf where it misses. The slab test in each
    box's own frame (x along its facing, y across, z up)."""
    for j in range(pos.shape[0]):
        c = math.cos(yaw[j])
        s = math.sin(yaw[j])
        rx = origin[0] - pos[j, 0]
        ry = origin[1] - pos[j, 1]
        o0 = c * rx + s * ry
        o1 = -s * rx + c * ry
        o2 = origin[2] - pos[j, 2]
        h0 = 0.5 * size[j, 1]
        h1 = 0.5 * size[j, 0]
        h2 = 0.5 * size[j, 2]
        for r in range(dirs.shape[0]):
            d0 = dirs[r, 0] * c + dirs[r, 1] * s
            d1 = -dirs[r, 0] * s + dirs[r, 1] * c
            d2 = dirs[r, 2]
            near = -np.inf
            far = np.inf
            for o, d, h in ((o0, d0, h0), (o1, d1, h1), (o2, d2, h2)):
                inv = 1.0 / (1e-12 if abs(d) < 1e-12 else d)
                t1 = (-h - o) * inv
                t2 = (h - o) * inv
                near = max(near, min(t1, t2))
                far = min(far, max(t1, t2))
            out[r, j] = max(near, 0.0) if far >= near and far > 0.0 else np.inf
