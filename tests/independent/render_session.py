#!/usr/bin/env python3
"""Independent photo-session generator for rtscalib (SPEC section 7).

Simulates a robotic total station with a zoom camera photographing printed
tag36h11 AprilTag boards, and writes

  session_photo/     images/*.png, shots.csv, targets.yaml (no board pose)
  session_surveyed/  same images and shots, targets.yaml with board 0's pose
  truth.json         every true parameter
  exact_pixels.csv   exact projections of every fully visible tag corner

Written from /work/shared/spec/SPEC.md only (no project code was read).
"SPEC n" below refers to a section of that file.

Usage:  python3 render_session.py [--out /work/indep] [--ss 4]
"""
import argparse
import ctypes
import csv
import json
import math
import os
import shutil
import sys
import time

import cv2
import numpy as np

ARCSEC = math.pi / (180.0 * 3600.0)
DEG = math.pi / 180.0

# ---------------------------------------------------------------------------
# Rotations.  SPEC 1: Euler angles [a, b, g] mean R = Rz(g) Ry(b) Rx(a).
# ---------------------------------------------------------------------------


def Rx(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]], float)


def Ry(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]], float)


def Rz(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]], float)


def euler_to_R(a, b, g):
    """SPEC 1 (paper Eq. 83): R = Rz(g) Ry(b) Rx(a), stored as [a, b, g]."""
    return Rz(g) @ Ry(b) @ Rx(a)


def R_to_euler(R):
    """Inverse of euler_to_R (valid away from b = +-pi/2)."""
    b = -math.asin(max(-1.0, min(1.0, R[2, 0])))
    a = math.atan2(R[2, 1], R[2, 2])
    g = math.atan2(R[1, 0], R[0, 0])
    return [a, b, g]


def homog(R, t):
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = t
    return T


def rot4(R):
    return homog(R, np.zeros(3))


# ---------------------------------------------------------------------------
# True parameters (everything written to truth.json).
# ---------------------------------------------------------------------------

IMAGE_W, IMAGE_H = 1280, 960          # both zooms

# ref_from_base: a few degrees about z, 1-2 mrad tilts, offset origin, so the
# reference frame is NOT the instrument frame.
BASE_EULER = [-1.0e-3, 1.5e-3, 3.0 * DEG]          # [a, b, g]
BASE_T = [10.0, 20.0, 1.5]
BASE = homog(euler_to_R(*BASE_EULER), BASE_T)

# Per-zoom camera: OpenCV intrinsics and 14 distortion coefficients in OpenCV
# order k1 k2 p1 p2 k3 k4 k5 k6 s1 s2 s3 s4 taux tauy (SPEC 2), and the camera
# tool flange_from_cam (line-of-sight frame <- camera frame).
CAMERAS = {
    0: dict(fx=1500.0, fy=1502.0, cx=645.0, cy=478.0,
            dist=[-0.08, 0.05, 2e-4, -1e-4, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0],
            tool_euler=[2.1e-3, -1.3e-3, 2.8e-3],
            tool_t=[0.020, -0.030, 0.050]),
    1: dict(fx=3500.0, fy=3503.0, cx=637.0, cy=484.0,
            dist=[0.03, 0.0, 1e-4, 5e-5, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0],
            tool_euler=[-1.7e-3, 2.5e-3, -1.1e-3],
            tool_t=[0.018, -0.027, 0.062]),
}
for _z, _c in CAMERAS.items():
    _c["K"] = np.array([[_c["fx"], 0, _c["cx"]], [0, _c["fy"], _c["cy"]], [0, 0, 1]], float)
    _c["D"] = np.array(_c["dist"], float)
    _c["tool"] = homog(euler_to_R(*_c["tool_euler"]), _c["tool_t"])
    # this generator's own distortion model does not implement the sensor tilt
    assert _c["D"][12] == 0 and _c["D"][13] == 0

# SPEC 4 effects (SI units: radians).
EFFECTS = {
    "hz_eccentricity": {"e": 8.0 * ARCSEC, "phi_e": 30.0 * DEG},
    "collimation": {"c": 15.0 * ARCSEC},
    "tilting_axis": {"i": 10.0 * ARCSEC},
    "vertical_index": {"v0": 12.0 * ARCSEC},
}

# Boards (SPEC 7).  Placement in the instrument's ideal base frame: direction
# (phi, theta) and distance of the centre of the tag area, plus a small yaw /
# pitch / roll away from facing the instrument exactly.
FAMILY = "tag36h11"
ROWS, COLS, TAG, SPACING = 4, 6, 0.12, 0.04
MARGIN = TAG + SPACING          # white paper beyond the outer black squares (>= one tag)
BOARD_PLACEMENT = [
    # first_id, phi (deg), theta (deg), dist (m), yaw, pitch, roll (deg)
    (0, 0.0, 86.0, 4.5, 12.0, -4.0, 1.5),
    (24, 90.0, 94.0, 5.5, -15.0, 3.0, -1.0),
    (48, 200.0, 91.5, 6.5, 8.0, 5.0, 0.7),
    (72, 290.0, 88.0, 5.0, -10.0, -6.0, -2.0),
]

# ---------------------------------------------------------------------------
# Instrument model (SPEC 1 and SPEC 4).
# ---------------------------------------------------------------------------


def true_angles(phi, theta):
    """SPEC 4: readings -> true angles phi*, theta*."""
    e = EFFECTS.get("hz_eccentricity")
    phis = phi + (e["e"] * math.sin(phi - e["phi_e"]) if e else 0.0)
    v = EFFECTS.get("vertical_index")
    thetas = theta + (v["v0"] if v else 0.0)
    return phis, thetas


def wobble(phi):
    """SPEC 4 axis_wobble: Rx(w cos(phi-phi_w)) Ry(w sin(phi-phi_w)).
    Not switched on in this data set (identity); uses the phi reading."""
    w = EFFECTS.get("axis_wobble")
    if not w:
        return np.eye(3)
    return Rx(w["w"] * math.cos(phi - w["phi_w"])) @ Ry(w["w"] * math.sin(phi - w["phi_w"]))


def base_from_flange(phi, theta):
    """SPEC 4 chain without base and tool:
    wobble(phi) * Rz(-phi*) * Ry(i) * Rx(-theta*) * Ry(c).
    With no effects this is SPEC 1's ideal line-of-sight frame Rz(-phi) Rx(-theta)."""
    phis, thetas = true_angles(phi, theta)
    i = EFFECTS["tilting_axis"]["i"] if "tilting_axis" in EFFECTS else 0.0
    c = EFFECTS["collimation"]["c"] if "collimation" in EFFECTS else 0.0
    R = wobble(phi) @ Rz(-phis) @ Ry(i) @ Rx(-thetas) @ Ry(c)
    return rot4(R)   # the axes intersect at the base origin


def ref_from_cam(phi, theta, zoom):
    """SPEC 4: base * wobble(phi) * Rz(-phi*) * Ry(i) * Rx(-theta*) * Ry(c) * tool."""
    return BASE @ base_from_flange(phi, theta) @ CAMERAS[zoom]["tool"]


def face2_of(phi, theta):
    """SPEC 1: face 2 of face-1 pointing (phi, theta) is (phi - pi mod 2pi, 2pi - theta)."""
    return (phi - math.pi) % (2 * math.pi), 2 * math.pi - theta


def ideal_pointing(p_base):
    """Face-1 pointing that puts an instrument-frame point on the ideal line of
    sight (SPEC 1: EDM point d*[sin phi sin theta, cos phi sin theta, cos theta])."""
    x, y, z = p_base
    return math.atan2(x, y) % (2 * math.pi), math.atan2(math.hypot(x, y), z)


def self_check_frames():
    """SPEC 1/2: ideal frame at phi=0, theta=pi/2 with identity tool looks along
    +y (north), image right (+u = camera x) is +x (east), image down is -z."""
    R = Rz(-0.0) @ Rx(-math.pi / 2)
    assert np.allclose(R[:, 2], [0, 1, 0]) and np.allclose(R[:, 0], [1, 0, 0])
    assert np.allclose(R[:, 1], [0, 0, -1])
    # ideal EDM formula (SPEC 1) equals the z column of Rz(-phi) Rx(-theta)
    for phi, th in [(0.3, 1.2), (2.5, 1.7), (4.0, 0.9)]:
        d = np.array([math.sin(phi) * math.sin(th), math.cos(phi) * math.sin(th), math.cos(th)])
        assert np.allclose((Rz(-phi) @ Rx(-th))[:, 2], d)
        # face 2: same direction, x and y axes reversed (image turned by 180 deg)
        p2, t2 = face2_of(phi, th)
        R1, R2 = Rz(-phi) @ Rx(-th), Rz(-p2) @ Rx(-t2)
        assert np.allclose(R1[:, 2], R2[:, 2]) and np.allclose(R1[:, :2], -R2[:, :2])


# ---------------------------------------------------------------------------
# Camera model: own implementation of OpenCV's distortion (checked against
# cv2.projectPoints) and a Newton inverse for the back-projection.
# ---------------------------------------------------------------------------


def distort_normalized(x, y, D):
    """OpenCV model (SPEC 2): undistorted normalized (x, y) -> distorted normalized."""
    k1, k2, p1, p2, k3, k4, k5, k6, s1, s2, s3, s4 = D[:12]
    r2 = x * x + y * y
    r4 = r2 * r2
    r6 = r4 * r2
    radial = (1 + k1 * r2 + k2 * r4 + k3 * r6) / (1 + k4 * r2 + k5 * r4 + k6 * r6)
    xd = x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x) + s1 * r2 + s2 * r4
    yd = y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y + s3 * r2 + s4 * r4
    return xd, yd


def project_normalized(x, y, cam):
    xd, yd = distort_normalized(x, y, cam["D"])
    return cam["fx"] * xd + cam["cx"], cam["fy"] * yd + cam["cy"]


def undistort_pixels(u, v, cam, iters=8):
    """Pixel (u, v) -> undistorted normalized (x, y) such that the OpenCV
    projection of the ray (x, y, 1) is (u, v).  Start from cv2.undistortPoints,
    then Newton with a central-difference Jacobian (converges to ~1e-15)."""
    pts = np.stack([u.ravel(), v.ravel()], axis=1).reshape(-1, 1, 2)
    crit = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 50, 1e-12)
    if hasattr(cv2, "undistortPointsIter"):  # OpenCV 4 (Debian 12: 4.6)
        und = cv2.undistortPointsIter(pts, cam["K"], cam["D"], None, None, crit)
    else:  # OpenCV 5 took the criteria into undistortPoints
        und = cv2.undistortPoints(pts, cam["K"], cam["D"], None, None, None, crit)
    und = und.reshape(-1, 2)
    x, y = und[:, 0].copy(), und[:, 1].copy()
    del und, pts
    xt = (u.ravel() - cam["cx"]) / cam["fx"]       # target distorted normalized
    yt = (v.ravel() - cam["cy"]) / cam["fy"]
    D = cam["D"]
    h = 1e-6
    for _ in range(iters):
        fx0, fy0 = distort_normalized(x, y, D)
        rx, ry = fx0 - xt, fy0 - yt
        a1, b1 = distort_normalized(x + h, y, D)
        a0, b0 = distort_normalized(x - h, y, D)
        j11, j21 = (a1 - a0) / (2 * h), (b1 - b0) / (2 * h)
        a1, b1 = distort_normalized(x, y + h, D)
        a0, b0 = distort_normalized(x, y - h, D)
        j12, j22 = (a1 - a0) / (2 * h), (b1 - b0) / (2 * h)
        det = j11 * j22 - j12 * j21
        x -= (j22 * rx - j12 * ry) / det
        y -= (-j21 * rx + j11 * ry) / det
        del a0, a1, b0, b1
        if max(np.abs(rx).max(), np.abs(ry).max()) < 1e-15:
            break
    return x.reshape(u.shape), y.reshape(u.shape)


def lagrange4(t):
    """Weights of the 4-point Lagrange interpolation at nodes -1, 0, 1, 2 for
    0 <= t < 1 (exact for cubics)."""
    return np.array([-t * (t - 1) * (t - 2) / 6, (t + 1) * (t - 1) * (t - 2) / 2,
                     -(t + 1) * t * (t - 2) / 2, (t + 1) * t * (t - 1) / 6])


def sample_rays(ss, cam):
    """Undistorted normalized (x, y) of every supersample (the sample_grid
    positions), shape (H*ss, W*ss) each.  The back-projection is smooth over
    the image: it is solved (undistort_pixels) at the pixel centres and two
    pixels beyond the border, and interpolated to the ss x ss sub-pixel
    positions with 4-point Lagrange weights along u, then v (error ~h^4
    times the fourth derivative, h = 1 px: far below 1e-6 px, which the
    caller's round trip through cv2.projectPoints checks), at a sixteenth of
    the Newton solves."""
    m = 2
    gu = np.arange(-m, IMAGE_W + m, dtype=np.float64)
    gv = np.arange(-m, IMAGE_H + m, dtype=np.float64)
    GU, GV = np.meshgrid(gu, gv)
    gx, gy = undistort_pixels(GU, GV, cam)
    del GU, GV
    # Offsets of the samples from their pixel centre: -1/2 + (k + 1/2)/ss.
    d = -0.5 + (np.arange(ss) + 0.5) / ss
    base = np.floor(d).astype(int)          # the node at or left of the sample
    t = d - base
    out = []
    for g in (gx, gy):
        cols = []                           # along u: (H + 2m, W) per sub-column
        for k in range(ss):
            w = lagrange4(t[k])
            acc = np.zeros((g.shape[0], IMAGE_W))
            for j in range(4):
                off = m + base[k] + j - 1
                acc += w[j] * g[:, off:off + IMAGE_W]
            cols.append(acc)
        full = np.empty((IMAGE_H * ss, IMAGE_W * ss))
        for kv in range(ss):                # then along v
            w = lagrange4(t[kv])
            for ku in range(ss):
                acc = np.zeros((IMAGE_H, IMAGE_W))
                for j in range(4):
                    off = m + base[kv] + j - 1
                    acc += w[j] * cols[ku][off:off + IMAGE_H]
                full[kv::ss, ku::ss] = acc
        out.append(full)
    return out[0], out[1]


def sample_grid(ss):
    """Supersample positions.  SPEC 2: pixel (0,0) is the centre of the top-left
    pixel, so pixel (i, j) covers [i-0.5, i+0.5] x [j-0.5, j+0.5]; the ss x ss
    samples sit at i - 0.5 + (k + 0.5)/ss.  Returned as a (H*ss, W*ss) grid."""
    us = (np.arange(IMAGE_W * ss) + 0.5) / ss - 0.5
    vs = (np.arange(IMAGE_H * ss) + 0.5) / ss - 0.5
    return np.meshgrid(us, vs)


# ---------------------------------------------------------------------------
# Boards and tags (SPEC 7).
# ---------------------------------------------------------------------------


class _ImageU8(ctypes.Structure):
    _fields_ = [("width", ctypes.c_int32), ("height", ctypes.c_int32),
                ("stride", ctypes.c_int32), ("buf", ctypes.POINTER(ctypes.c_uint8))]


def load_tag_images(n_ids):
    """Bit images of tag36h11 ids 0..n_ids-1 from the system libapriltag:
    10 x 10 bits, the outer ring white, the inner 8 x 8 = the black square."""
    import glob
    path = sorted(glob.glob("/usr/lib/x86_64-linux-gnu/libapriltag.so*"))[0]
    lib = ctypes.CDLL(path)
    lib.tag36h11_create.restype = ctypes.c_void_p
    lib.apriltag_to_image.restype = ctypes.POINTER(_ImageU8)
    lib.apriltag_to_image.argtypes = [ctypes.c_void_p, ctypes.c_int]
    fam = lib.tag36h11_create()
    out = np.zeros((n_ids, 10, 10), np.float64)
    for k in range(n_ids):
        im = lib.apriltag_to_image(fam, k).contents
        assert im.width == 10 and im.height == 10
        a = np.ctypeslib.as_array(im.buf, (im.height * im.stride,)).reshape(im.height, im.stride)
        out[k] = a[:, :im.width] / 255.0
    # structure check: white outer ring, black border ring of the 8 x 8 square
    assert np.all(out[:, 0, :] == 1) and np.all(out[:, 9, :] == 1)
    assert np.all(out[:, :, 0] == 1) and np.all(out[:, :, 9] == 1)
    assert np.all(out[:, 1, 1:9] == 0) and np.all(out[:, 8, 1:9] == 0)
    assert np.all(out[:, 1:9, 1] == 0) and np.all(out[:, 1:9, 8] == 0)
    return out


def tag_area_size():
    return (COLS * TAG + (COLS - 1) * SPACING, ROWS * TAG + (ROWS - 1) * SPACING)


def make_boards():
    """ref_from_board for every board.  SPEC 7 board frame: x right along a row,
    y down a column, z out of the back (a camera facing the print looks along +z);
    origin = top-left corner of tag (0,0)'s black square."""
    Wt, Ht = tag_area_size()
    Rbase, tbase = BASE[:3, :3], BASE[:3, 3]
    boards = []
    for first_id, phi_d, th_d, dist, yaw, pitch, roll in BOARD_PLACEMENT:
        phi, th = phi_d * DEG, th_d * DEG
        # centre of the tag area, instrument (base) frame
        c_base = dist * np.array([math.sin(phi) * math.sin(th), math.cos(phi) * math.sin(th), math.cos(th)])
        # facing the instrument, upright: z = horizontal direction away from the
        # instrument, y = down (-z of the world), x = y cross z
        z = np.array([math.sin(phi), math.cos(phi), 0.0])
        y = np.array([0.0, 0.0, -1.0])
        x = np.cross(y, z)
        R0 = np.column_stack([x, y, z])
        # small misalignment in the board's own axes: yaw about y, pitch about x, roll about z
        Rb_base = R0 @ Ry(yaw * DEG) @ Rx(pitch * DEG) @ Rz(roll * DEG)
        o_base = c_base - Rb_base @ np.array([Wt / 2, Ht / 2, 0.0])
        R = Rbase @ Rb_base
        t = Rbase @ o_base + tbase
        boards.append(dict(first_id=first_id, rows=ROWS, cols=COLS, tag_size=TAG, spacing=SPACING,
                           ref_from_board=homog(R, t), centre_base=c_base))
    return boards


def tag_corners_board(r, c):
    """SPEC 7: corners 0..3 = bottom-left, bottom-right, top-right, top-left of
    the upright printed tag; the board's y axis points down, so 'bottom' = +y."""
    x0, y0 = (TAG + SPACING) * c, (TAG + SPACING) * r
    return np.array([[x0, y0 + TAG, 0], [x0 + TAG, y0 + TAG, 0],
                     [x0 + TAG, y0, 0], [x0, y0, 0]], float)


# ---------------------------------------------------------------------------
# Rendering.
# ---------------------------------------------------------------------------

BACKGROUND = 0.35


def board_value(bx, by, board, tagimgs):
    """Reflectance at board coordinates (paper white = 1, black bit = 0)."""
    pitch = TAG + SPACING
    c = np.floor(bx / pitch).astype(np.int64)
    r = np.floor(by / pitch).astype(np.int64)
    rx, ry = bx - c * pitch, by - r * pitch
    inside = (c >= 0) & (c < COLS) & (r >= 0) & (r < ROWS) & (rx < TAG) & (ry < TAG)
    val = np.ones(bx.shape)
    if inside.any():
        bit = TAG / 8.0
        # the black square is bits 1..8 of the 10 x 10 libapriltag image;
        # image row = board y (down), image column = board x (right)
        ix = np.clip(np.floor(rx[inside] / bit).astype(np.int64), 0, 7) + 1
        iy = np.clip(np.floor(ry[inside] / bit).astype(np.int64), 0, 7) + 1
        tid = board["first_id"] + r[inside] * COLS + c[inside]
        val[inside] = tagimgs[tid, iy, ix]
    return val


TILE_ROWS, TILE_COLS = 240, 640            # supersamples per tile
_tile_boxes = {}


def tile_boxes(rays):
    """Per tile of the supersample grid: the range of its rays' normalized
    x and y, (rows, cols, 4) = [xmin, xmax, ymin, ymax]; cached per ray set."""
    key = id(rays[0])
    if key not in _tile_boxes:
        rx, ry = rays
        nr, nc = -(-rx.shape[0] // TILE_ROWS), -(-rx.shape[1] // TILE_COLS)
        box = np.empty((nr, nc, 4))
        for i in range(nr):
            for j in range(nc):
                tx = rx[i * TILE_ROWS:(i + 1) * TILE_ROWS, j * TILE_COLS:(j + 1) * TILE_COLS]
                ty = ry[i * TILE_ROWS:(i + 1) * TILE_ROWS, j * TILE_COLS:(j + 1) * TILE_COLS]
                box[i, j] = tx.min(), tx.max(), ty.min(), ty.max()
        _tile_boxes[key] = box
    return _tile_boxes[key]


def board_box(b, Rc, tc):
    """Range of normalized x and y of the board's area (with MARGIN) seen
    from the camera, or None when part of it is not in front of the camera
    (then no tile is skipped for it).  A plane quadrilateral projects to a
    quadrilateral: its corners bound it."""
    Wt, Ht = tag_area_size()
    Rb, tb = b["ref_from_board"][:3, :3], b["ref_from_board"][:3, 3]
    xs, ys = [], []
    for bx, by in ((-MARGIN, -MARGIN), (Wt + MARGIN, -MARGIN), (-MARGIN, Ht + MARGIN),
                   (Wt + MARGIN, Ht + MARGIN)):
        p = Rc.T @ (Rb @ np.array([bx, by, 0.0]) + tb - tc)
        if p[2] <= 1e-9:
            return None
        xs.append(p[0] / p[2])
        ys.append(p[1] / p[2])
    return min(xs), max(xs), min(ys), max(ys)


_canvas = {}


def render(T_ref_cam, rays, boards, tagimgs, ss):
    """Mean reflectance per pixel over the ss x ss samples (box filter).
    Tiles of samples whose rays cannot meet a board are left background."""
    rx_all, ry_all = rays
    Rc, tc = T_ref_cam[:3, :3], T_ref_cam[:3, 3]
    Wt, Ht = tag_area_size()
    visible = []
    for b in boards:
        Rb, tb = b["ref_from_board"][:3, :3], b["ref_from_board"][:3, 3]
        o = Rb.T @ (tc - tb)                      # camera centre in the board frame
        if o[2] >= 0:                             # behind the board: back side only
            continue
        cen = Rb @ np.array([Wt / 2, Ht / 2, 0]) + tb
        dirn = (cen - tc) / np.linalg.norm(cen - tc)
        if dirn @ Rc[:, 2] < math.cos(1.0):       # far outside the field of view
            continue
        visible.append((b, Rb.T @ Rc, o, board_box(b, Rc, tc)))
    # One supersampled canvas per size, reused: a fresh array of this size
    # (150 MB at ss = 4) costs more in page faults than the rendering itself.
    shape = (IMAGE_H * ss, IMAGE_W * ss)
    if shape not in _canvas:
        _canvas[shape] = np.empty(shape)
    out = _canvas[shape]
    out.fill(BACKGROUND)
    boxes = tile_boxes(rays)
    for i in range(boxes.shape[0]):
        for j in range(boxes.shape[1]):
            xmin, xmax, ymin, ymax = boxes[i, j]
            here = [(b, M, o) for b, M, o, bb in visible
                    if bb is None or not (bb[1] < xmin or bb[0] > xmax or bb[3] < ymin or bb[2] > ymax)]
            if not here:
                continue
            rows = slice(i * TILE_ROWS, (i + 1) * TILE_ROWS)
            cols = slice(j * TILE_COLS, (j + 1) * TILE_COLS)
            x, y = rx_all[rows, cols], ry_all[rows, cols]
            val = out[rows, cols]                 # a view: written in place
            tbest = np.full(x.shape, np.inf)
            for b, M, o in here:
                # ray (x, y, 1) in camera frame -> board frame, intersect z = 0
                dz = M[2, 0] * x + M[2, 1] * y + M[2, 2]
                with np.errstate(divide="ignore", invalid="ignore"):
                    t = np.where(dz > 0, -o[2] / dz, np.inf)   # front side only
                bx = o[0] + t * (M[0, 0] * x + M[0, 1] * y + M[0, 2])
                by = o[1] + t * (M[1, 0] * x + M[1, 1] * y + M[1, 2])
                on = (t < tbest) & (bx >= -MARGIN) & (bx <= Wt + MARGIN) & (by >= -MARGIN) & (by <= Ht + MARGIN)
                if on.any():
                    val[on] = board_value(bx[on], by[on], b, tagimgs)
                    tbest[on] = t[on]
    # The ss x ss box mean (OpenCV's area resampling at an integer factor is
    # exactly that mean, several times faster than numpy's over two axes).
    return cv2.resize(out, (IMAGE_W, IMAGE_H), interpolation=cv2.INTER_AREA)


# ---------------------------------------------------------------------------
# Exact corner projections.
# ---------------------------------------------------------------------------


def exact_corners(T_ref_cam, zoom, boards):
    """Every tag whose 4 black-square corners project inside the image (pixel
    centre range [0, W-1] x [0, H-1]) on the printed side in front of the camera.
    Returns list of (tag id, corner, X_ref(3), u, v)."""
    cam = CAMERAS[zoom]
    T_cam_ref = np.linalg.inv(T_ref_cam)
    rows = []
    for b in boards:
        Tb = b["ref_from_board"]
        if (np.linalg.inv(Tb) @ T_ref_cam[:, 3])[2] >= 0:   # camera behind the board
            continue
        for r in range(ROWS):
            for c in range(COLS):
                P_board = tag_corners_board(r, c)
                P_ref = (Tb[:3, :3] @ P_board.T).T + Tb[:3, 3]
                P_cam = (T_cam_ref[:3, :3] @ P_ref.T).T + T_cam_ref[:3, 3]
                if np.any(P_cam[:, 2] <= 0):
                    continue
                xn = P_cam[:, :2] / P_cam[:, 2:3]
                if np.any(np.hypot(xn[:, 0], xn[:, 1]) > 1.0):   # stay where distortion is monotonic
                    continue
                uv, _ = cv2.projectPoints(P_cam.reshape(-1, 1, 3), np.zeros(3), np.zeros(3), cam["K"], cam["D"])
                uv = uv.reshape(-1, 2)
                if np.all((uv[:, 0] >= 0) & (uv[:, 0] <= IMAGE_W - 1) & (uv[:, 1] >= 0) & (uv[:, 1] <= IMAGE_H - 1)):
                    tid = b["first_id"] + r * COLS + c
                    for k in range(4):
                        rows.append((tid, k, P_ref[k], uv[k, 0], uv[k, 1]))
    return rows


# ---------------------------------------------------------------------------
# Shot plan.
# ---------------------------------------------------------------------------


def round12(x):
    return float("%.12g" % x)


def zoom0_cells(rng):
    """Zoom 0 (boards ~300 x 200 px): a 6 x 5 grid of board-centre positions.
    Face 2 shows the point-reflected position (image turned by 180 deg), so
    face-1 pointings take one cell of each reflected pair (15 cells), plus the
    other cell of 5 pairs (incl. both corner pairs): 20 face-1 shots, and every
    cell is seen at least once.  Shuffled, then 5 cells per board."""
    ncol, nrow = 6, 5
    n = ncol * nrow
    cells = [k if k % 2 == 0 else n - 1 - k for k in range(n // 2)]
    cells += [n - 1 - k for k in (0, 2, 12)] + [k for k in (5, 7)]
    assert len(set(cells)) == 20
    cells = [cells[i] for i in rng.permutation(len(cells))]
    return [[(c % ncol, c // ncol) for c in cells[5 * b:5 * b + 5]] for b in range(4)], ncol, nrow


def plan_shots(boards, rng):
    """Per board and zoom: 5 face-1 pointings, each followed by its face-2
    pointing (SPEC 1).  Zoom 0: cells of a 6 x 5 grid (zoom0_cells).  Zoom 1
    (boards ~700 x 470 px): board centre at the image corners + centre (boards
    0, 2) or the edge middles + centre (boards 1, 3).  Outer positions put the
    board ~0.2 of its half size past the image edge (partial boards)."""
    Rbase_inv = np.linalg.inv(BASE)
    z0cells, ncol, nrow = zoom0_cells(rng)
    shots = []
    for bi, b in enumerate(boards):
        Wt, Ht = tag_area_size()
        Tb = b["ref_from_board"]
        c_ref = Tb[:3, :3] @ np.array([Wt / 2, Ht / 2, 0]) + Tb[:3, 3]
        c_base = (Rbase_inv @ np.append(c_ref, 1))[:3]
        phi_t, th_t = ideal_pointing(c_base)
        dist = np.linalg.norm(c_base)
        for zoom in (0, 1):
            cam = CAMERAS[zoom]
            hw = cam["fx"] * Wt / 2 / dist        # half size of the tag area, px
            hh = cam["fy"] * Ht / 2 / dist
            ax = IMAGE_W / 2 - 0.8 * hw           # board reaches ~0.2 hw past the edge
            ay = IMAGE_H / 2 - 0.8 * hh
            if zoom == 0:
                us, vs = np.linspace(-ax, ax, ncol), np.linspace(-ay, ay, nrow)
                offs = [(us[c], vs[r]) for c, r in z0cells[bi]]
            elif bi % 2 == 0:
                offs = [(0, 0), (-ax, -ay), (ax, -ay), (ax, ay), (-ax, ay)]
            else:
                offs = [(0, 0), (0, -ay), (ax, 0), (0, ay), (-ax, 0)]
            for (a, bb) in offs:
                a += rng.uniform(-15, 15)
                bb += rng.uniform(-15, 15)
                # board centre at image position (cx + a, cy + bb): look left/up of it
                # (face 1: +u is +phi, +v is +theta)
                phi1 = (phi_t - a / cam["fx"] / math.sin(th_t)) % (2 * math.pi)
                th1 = th_t - bb / cam["fy"]
                phi2, th2 = face2_of(phi1, th1)
                shots.append(dict(face=1, zoom=zoom, phi=round12(phi1), theta=round12(th1), board=bi))
                shots.append(dict(face=2, zoom=zoom, phi=round12(phi2), theta=round12(th2), board=bi))
    # 16-bit for every 5th image of zoom 1
    n1 = 0
    for k, s in enumerate(shots):
        s["name"] = "s%03d" % (k + 1)
        if s["zoom"] == 1:
            n1 += 1
        s["bits"] = 16 if (s["zoom"] == 1 and n1 % 5 == 0) else 8
    return shots


# ---------------------------------------------------------------------------
# Output.
# ---------------------------------------------------------------------------


def write_targets(path, boards, pose_for=()):
    with open(path, "w") as f:
        f.write("# independent test data (SPEC 7); board frame: x right, y down, z out of the back\n")
        f.write("boards:\n")
        for k, b in enumerate(boards):
            line = ("  - {family: %s, first_id: %d, rows: %d, cols: %d, tag_size: %r, spacing: %r"
                    % (FAMILY, b["first_id"], b["rows"], b["cols"], float(b["tag_size"]), float(b["spacing"])))
            if k in pose_for:
                T = b["ref_from_board"]
                e = R_to_euler(T[:3, :3])
                assert np.allclose(euler_to_R(*e), T[:3, :3], atol=1e-14)
                line += (",\n     pose: {euler: [%r, %r, %r], t: [%r, %r, %r]}"
                         % tuple(float(x) for x in (e[0], e[1], e[2], T[0, 3], T[1, 3], T[2, 3])))
            f.write(line + "}\n")


def write_shots_csv(path, shots):
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["face", "zoom", "phi", "theta", "image"])
        for s in shots:
            w.writerow([s["face"], s["zoom"], "%.12g" % s["phi"], "%.12g" % s["theta"], "images/%s.png" % s["name"]])


def truth_dict(boards, shots, ss, noise):
    cams = {}
    for z, c in CAMERAS.items():
        cams[str(z)] = dict(fx=c["fx"], fy=c["fy"], cx=c["cx"], cy=c["cy"],
                            dist_names="k1 k2 p1 p2 k3 k4 k5 k6 s1 s2 s3 s4 taux tauy".split(),
                            dist=list(c["D"]),
                            flange_from_cam=c["tool"].tolist(),
                            flange_from_cam_euler=c["tool_euler"], flange_from_cam_t=c["tool_t"])
    effects = {}
    for name, p in EFFECTS.items():
        effects[name] = dict(p)
        effects[name]["report_units"] = {k: (v / ARCSEC if k in ("e", "c", "i", "v0", "w") else v / DEG)
                                         for k, v in p.items()}
    return dict(
        note="independent generator /work/indep/render_session.py; SI units (m, rad)",
        image_size=[IMAGE_W, IMAGE_H],
        chain="ref_from_cam = base * wobble(phi) * Rz(-phi*) * Ry(i) * Rx(-theta*) * Ry(c) * flange_from_cam[zoom]",
        base_ref_from_base=BASE.tolist(), base_euler=BASE_EULER, base_t=BASE_T,
        cameras=cams,
        effects=effects,
        effects_absent=["axis_wobble", "v_eccentricity", "hz_scale", "v_scale", "edm_*", "thin_prism", "sensor_tilt",
                        "rational_distortion (k3..k6 = 0)"],
        boards=[dict(family=FAMILY, first_id=b["first_id"], rows=b["rows"], cols=b["cols"], tag_size=b["tag_size"],
                     spacing=b["spacing"], paper_margin=MARGIN,
                     ref_from_board=b["ref_from_board"].tolist(),
                     ref_from_board_euler=R_to_euler(b["ref_from_board"][:3, :3]),
                     ref_from_board_t=b["ref_from_board"][:3, 3].tolist(),
                     # session_photo has no known position, so there the reference frame is the
                     # instrument's ideal base frame (SPEC 7): compare boards with this one
                     base_from_board=(np.linalg.inv(BASE) @ b["ref_from_board"]).tolist())
                for b in boards],
        gauge_note=("session_surveyed: reference frame fixed by board 0's pose, so base_ref_from_base applies. "
                    "session_photo: no known position, reference = instrument base frame (base = identity); "
                    "boards then equal base_from_board. exact_pixels.csv X,Y,Z are in the surveyed reference frame."),
        versions=dict(numpy=np.__version__, opencv=cv2.__version__),
        rendering=dict(supersample=ss, intensity="30 + 190*reflectance + N(0, %g), rounded" % noise,
                       background_reflectance=BACKGROUND, sixteen_bit="value*257",
                       sixteen_bit_images=[s["name"] for s in shots if s["bits"] == 16]),
        shots=[dict(name=s["name"], face=s["face"], zoom=s["zoom"], phi=s["phi"], theta=s["theta"],
                    board_aimed=s["board"], bits=s["bits"]) for s in shots],
    )


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", default="/work/indep")
    ap.add_argument("--ss", type=int, default=4, help="supersamples per pixel side")
    ap.add_argument("--noise", type=float, default=1.0)
    ap.add_argument("--seed", type=int, default=20240611)
    ap.add_argument("--only", type=int, default=0, help="render only the first N shots (debug)")
    args = ap.parse_args()
    t_start = time.time()
    rng = np.random.default_rng(args.seed)

    self_check_frames()
    boards = make_boards()
    tagimgs = load_tag_images(boards[-1]["first_id"] + ROWS * COLS)
    shots = plan_shots(boards, rng)
    if args.only:
        shots = shots[:args.only]

    photo = os.path.join(args.out, "session_photo")
    surveyed = os.path.join(args.out, "session_surveyed")
    for d in (photo, surveyed):
        os.makedirs(os.path.join(d, "images"), exist_ok=True)

    # --- own distortion model == cv2.projectPoints (SPEC 2) -----------------
    for z, cam in CAMERAS.items():
        P = np.column_stack([rng.uniform(-0.5, 0.5, 2000), rng.uniform(-0.4, 0.4, 2000), np.ones(2000)])
        uv, _ = cv2.projectPoints(P.reshape(-1, 1, 3), np.zeros(3), np.zeros(3), cam["K"], cam["D"])
        u, v = project_normalized(P[:, 0], P[:, 1], cam)
        err = np.abs(np.column_stack([u, v]) - uv.reshape(-1, 2)).max()
        print("zoom %d: own projection vs cv2.projectPoints max diff %.2e px" % (z, err))
        assert err < 1e-8

    # --- rays per zoom, computed once (SPEC 2 back-projection) --------------
    U, V = sample_grid(args.ss)
    rays = {}
    for z, cam in CAMERAS.items():
        t0 = time.time()
        x, y = sample_rays(args.ss, cam)
        rays[z] = (x, y)
        # self-check (1): cv2.projectPoints of the ray returns the sample pixel
        idx = np.concatenate([rng.integers(0, U.size, 200000),
                              [0, IMAGE_W * args.ss - 1, U.size - IMAGE_W * args.ss, U.size - 1]])
        P = np.column_stack([x.ravel()[idx], y.ravel()[idx], np.ones(idx.size)])
        uv, _ = cv2.projectPoints(P.reshape(-1, 1, 3), np.zeros(3), np.zeros(3), cam["K"], cam["D"])
        err = np.abs(uv.reshape(-1, 2) - np.column_stack([U.ravel()[idx], V.ravel()[idx]])).max()
        print("zoom %d: %d rays in %.1f s; round trip cv2.projectPoints(ray) - pixel: max %.2e px"
              % (z, U.size, time.time() - t0, err))
        assert err < 1e-6
    del U, V

    # --- render ---------------------------------------------------------------
    t_render = time.time()
    exact_rows = []
    for k, s in enumerate(shots):
        t0 = time.time()
        T = ref_from_cam(s["phi"], s["theta"], s["zoom"])
        refl = render(T, rays[s["zoom"]], boards, tagimgs, args.ss)
        img = np.clip(np.rint(30.0 + 190.0 * refl + rng.normal(0.0, args.noise, refl.shape)), 0, 255)
        path = os.path.join(photo, "images", s["name"] + ".png")
        if s["bits"] == 16:
            cv2.imwrite(path, (img * 257).astype(np.uint16))
        else:
            cv2.imwrite(path, img.astype(np.uint8))
        shutil.copyfile(path, os.path.join(surveyed, "images", s["name"] + ".png"))
        ex = exact_corners(T, s["zoom"], boards)
        for tid, corner, X, u, v in ex:
            exact_rows.append((s["face"], s["zoom"], s["phi"], s["theta"], s["name"], tid, corner, X, u, v))
        print("%s face %d zoom %d phi %.6f theta %.6f bits %d: %d tags exact, %.1f s"
              % (s["name"], s["face"], s["zoom"], s["phi"], s["theta"], s["bits"], len(ex) // 4, time.time() - t0))
        sys.stdout.flush()
    t_render = time.time() - t_render

    # --- files ----------------------------------------------------------------
    for d in (photo, surveyed):
        write_shots_csv(os.path.join(d, "shots.csv"), shots)
    write_targets(os.path.join(photo, "targets.yaml"), boards)
    write_targets(os.path.join(surveyed, "targets.yaml"), boards, pose_for=(0,))
    with open(os.path.join(args.out, "exact_pixels.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["face", "zoom", "phi", "theta", "shot", "target", "corner", "X", "Y", "Z", "u", "v"])
        for face, zoom, phi, th, name, tid, corner, X, u, v in exact_rows:
            w.writerow([face, zoom, "%.12g" % phi, "%.12g" % th, name, tid, corner,
                        "%.12f" % X[0], "%.12f" % X[1], "%.12f" % X[2], "%.9f" % u, "%.9f" % v])
    truth = truth_dict(boards, shots, args.ss, args.noise)
    truth["render_seconds"] = t_render
    with open(os.path.join(args.out, "truth.json"), "w") as f:
        json.dump(truth, f, indent=1)
    counts = {}
    for s in shots:
        counts[(s["zoom"], s["face"])] = counts.get((s["zoom"], s["face"]), 0) + 1
    print("photos per (zoom, face):", counts, " exact corners:", len(exact_rows))
    print("render %.1f s, total %.1f s" % (t_render, time.time() - t_start))


if __name__ == "__main__":
    main()
