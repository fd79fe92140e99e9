"""Finding the board in a photo: its inner corners, to a tenth of a pixel.

OpenCV's checkerboard detectors (the sector-based one, then the classic one) on the whole
photo, then on crops around groups of saddle points and on an affine view that undoes a
far board's squash; ChArUco boards through their markers. Every grid found must be the
board: its squares alternate as printed and it is not a patch of a larger board.
"""
from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from .board import CHARUCO_BITS_PER_SQUARE, CHARUCO_MARKER_BITS, Board, charuco_board
from .settings import CAMERA

_SUBPIX_CRITERIA = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 40, 1e-3)
_SB_FLAGS = cv2.CALIB_CB_NORMALIZE_IMAGE | cv2.CALIB_CB_EXHAUSTIVE
_CLASSIC_FLAGS = cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE
# Board sizes people print; tried only to suggest a fix when the given size is not found.
_COMMON_SIZES = ((9, 6), (8, 6), (7, 5), (7, 6), (6, 4), (8, 5), (10, 7), (6, 9), (5, 7))


@dataclass(frozen=True)
class BoardDetection:
    """The board's inner corners found in a photo.

    Attributes
    ----------
    corners_px : (n, 2) float64
        Corner positions, full resolution, refined to the saddle point of the intensity.
    ids : (n,) int64
        Which corner of the board each one is: the row of :meth:`Board.corners_m`. A
        checkerboard gives all ``cols * rows`` in the detector's order (which may read the
        board mirrored: :func:`calibrate_photo` settles that from the pose); a ChArUco
        board gives the corners it shows, at least ``CAMERA.detect.min_charuco_corners``.
    detector : str
        ``"sb"`` or ``"classic"`` (OpenCV's checkerboard detectors), with ``" crop"`` when
        found only on a crop around the board, ``" rectified"`` when only on a view of it
        with its foreshortening undone (:func:`_find_rectified`); ``"charuco"`` when a
        ChArUco board's markers were read (a ChArUco board whose markers are not read is
        found as a checkerboard, by those names).
    """

    corners_px: np.ndarray
    ids: np.ndarray
    detector: str

    def object_points_m(self, board: Board) -> np.ndarray:
        """The detected corners in the board frame, (n, 3) meters."""
        return board.corners_m()[self.ids]


def _gray(image: np.ndarray) -> np.ndarray:
    image = np.asarray(image)
    if image.ndim == 2:
        return image if image.dtype == np.uint8 else cv2.convertScaleAbs(image)
    if image.ndim == 3 and image.shape[2] in (3, 4):
        return cv2.cvtColor(image[..., :3], cv2.COLOR_RGB2GRAY)
    raise ValueError(f"image of shape {image.shape}: expected (h, w) gray or (h, w, 3) RGB")


def corner_spacing_px(corners_px: np.ndarray, ids: np.ndarray, board: Board) -> float:
    """The smallest distance between detected corners that are neighbors on the board, px.

    Parameters
    ----------
    corners_px : (n, 2) float
    ids : (n,) int
        Board corner numbers (:class:`BoardDetection`).
    board : Board
    """
    corners = np.asarray(corners_px, dtype=np.float64).reshape(-1, 2)
    ids = np.asarray(ids, dtype=np.int64)
    grid = np.full((board.rows * board.cols, 2), np.nan)
    grid[ids] = corners
    grid = grid.reshape(board.rows, board.cols, 2)
    steps = np.concatenate([np.linalg.norm(np.diff(grid, axis=0), axis=-1).ravel(),
                            np.linalg.norm(np.diff(grid, axis=1), axis=-1).ravel()])
    steps = steps[np.isfinite(steps)]
    if len(steps):
        return float(steps.min())
    # No two neighbors (a sparse ChArUco view): the nearest pair, over its board distance.
    d_px = np.linalg.norm(corners[:, None] - corners[None], axis=-1)
    row, col = np.divmod(ids, board.cols)
    d_sq = np.hypot(row[:, None] - row[None], col[:, None] - col[None])
    np.fill_diagonal(d_sq, np.inf)
    return float(np.min(d_px / d_sq))


def _saddle_refine(gray: np.ndarray, corners: np.ndarray, radius: int) -> tuple[np.ndarray, np.ndarray]:
    """Corners moved to the saddle point of the intensity around them.

    A quadratic surface is fit by weighted least squares (Gaussian weights, sd half the
    radius) to a ``2 radius + 1`` window resampled centered on the current estimate, and
    the estimate moved to the surface's saddle point until it stops moving. The window is
    symmetric about the corner, so the blur and the tone curve of a photo, both symmetric
    about an X-junction, do not bias it: it lands closer to the truth than ``cornerSubPix``,
    whose errors on small, foreshortened boards cost several percent of focal length.

    Returns
    -------
    refined : (n, 2) float64
        Where a corner did not converge (no saddle, or it wandered off) its input is kept.
    converged : (n,) bool
    """
    n = 2 * radius + 1
    offsets = np.arange(-radius, radius + 1, dtype=np.float64)
    y, x = np.meshgrid(offsets, offsets, indexing="ij")
    x, y = x.ravel(), y.ravel()
    weight = np.exp(-(x * x + y * y) / (2 * (0.5 * radius) ** 2))
    fit = np.linalg.pinv(np.column_stack([x * x, x * y, y * y, x, y, np.ones_like(x)]) * weight[:, None])
    image = gray.astype(np.float32)
    refined = np.array(corners, dtype=np.float64).reshape(-1, 2)
    converged = np.zeros(len(refined), bool)
    for k, start in enumerate(refined.copy()):
        p = start.copy()
        for _ in range(20):
            patch = cv2.getRectSubPix(image, (n, n), (float(p[0]), float(p[1])))
            a, b, c, d, e, _ = fit @ (patch.ravel().astype(np.float64) * weight)
            hessian = np.array([[2 * a, b], [b, 2 * c]])
            if np.linalg.det(hessian) >= 0:  # not a saddle
                break
            step = np.linalg.solve(hessian, -np.array([d, e]))
            p = p + step
            if np.abs(step).max() > radius or np.linalg.norm(p - start) > radius:
                break
            if np.linalg.norm(step) < 0.005:
                refined[k], converged[k] = p, True
                break
    return refined, converged


def _refine(gray: np.ndarray, corners: np.ndarray, ids: np.ndarray, board: Board) -> np.ndarray:
    """Full-resolution corners: saddle points; a checkerboard corner where no saddle
    converges falls back to ``cornerSubPix`` (ChArUco corners come refined by OpenCV)."""
    settings = CAMERA.detect
    spacing = corner_spacing_px(corners, ids, board)
    radius = int(np.clip(round(settings.saddle_window[board.kind] * spacing), 2, settings.max_saddle_radius_px))
    refined, converged = _saddle_refine(gray, corners, radius)
    if board.kind == "chessboard" and not converged.all():
        # The search window must stay inside one square, or a neighbouring corner pulls.
        half = int(np.clip(0.4 * spacing, 2, 11))
        rest = cv2.cornerSubPix(gray, refined[~converged].reshape(-1, 1, 2).astype(np.float32), (half, half),
                                (-1, -1), _SUBPIX_CRITERIA)
        refined[~converged] = rest.reshape(-1, 2)
    return _mend_outliers(gray, refined, ids, board, spacing, radius)


def _neighbours_say(corners: np.ndarray, ids: np.ndarray, board: Board) -> np.ndarray:
    """(n, 2): where each corner's neighbours on the board (up to
    ``CAMERA.detect.outlier_reach`` corners away, the corner itself left out) put it
    through a homography; NaN where fewer than 6 are detected."""
    reach = CAMERA.detect.outlier_reach
    grid = np.column_stack(np.divmod(ids, board.cols))
    on_board = board.corners_m()[ids][:, :2]
    out = np.full((len(ids), 2), np.nan)
    for i in range(len(ids)):
        near = np.abs(grid - grid[i]).max(axis=1) <= reach
        near[i] = False
        if near.sum() < 6:
            continue
        H, _ = cv2.findHomography(on_board[near], corners[near], 0)
        if H is not None:
            out[i] = cv2.perspectiveTransform(on_board[i].reshape(1, 1, 2), H).reshape(2)
    return out


def _mend_outliers(gray: np.ndarray, corners: np.ndarray, ids: np.ndarray, board: Board, spacing: float,
                   radius: int) -> np.ndarray:
    """``corners`` with those far from where their neighbours put them searched again
    from there (``CAMERA.detect.outlier_squares``), worst first, or else moved there.

    Now and then a detector puts a corner of a small board a good part of a square off,
    where the saddle search does not reach the true corner, and one such corner can tip
    the floor's tilt. The neighbours' homography is local, so lens distortion does not
    matter.
    """
    corners = corners.copy()
    limit = max(CAMERA.detect.outlier_squares * spacing, 1.0)
    mended = set()
    while len(mended) < len(ids) // 4:
        said = _neighbours_say(corners, ids, board)
        off = np.linalg.norm(said - corners, axis=1)
        if not np.isfinite(off).any():
            break
        i = int(np.nanargmax(off))
        if off[i] <= limit or i in mended:
            break
        mended.add(i)
        found, converged = _saddle_refine(gray, said[i][None], radius)
        near = converged[0] and np.linalg.norm(found[0] - said[i]) < limit
        corners[i] = found[0] if near else said[i]
    return corners


def square_contrast(gray: np.ndarray, corners_px: np.ndarray, board: Board) -> np.ndarray:
    """How each square outlined by a checkerboard's corners differs from its neighbours,
    the way the printed board alternates, in units of the median inner square's difference.

    Parameters
    ----------
    gray : (h, w) uint8
    corners_px : (cols * rows, 2) float
        All inner corners, in :meth:`Board.corners_m` order (or the detector's: mirrored
        or turned readings give the same values).
    board : Board

    Returns
    -------
    (rows + 1, cols + 1) float64
        One per printed square, the ring outside the inner corners included: about 1 for a
        square as dark or light as printed against its neighbours, negative for one the
        wrong way round.
    """
    on_board = board.corners_m()[:, :2]
    H, _ = cv2.findHomography(on_board, np.asarray(corners_px, np.float64).reshape(-1, 2), 0)
    offsets = np.linspace(-0.25, 0.25, 3) * board.square_m
    du, dv = (a.ravel() for a in np.meshgrid(offsets, offsets))
    row, col = np.mgrid[-1:board.rows, -1:board.cols]
    x = ((col + 0.5 - (board.cols - 1) / 2) * board.square_m)[..., None] + du
    y = ((row + 0.5 - (board.rows - 1) / 2) * board.square_m)[..., None] + dv
    px = cv2.perspectiveTransform(np.stack([x, y], -1).reshape(-1, 1, 2), H).reshape(1, -1, 2).astype(np.float32)
    value = cv2.remap(gray, px[..., 0].copy(), px[..., 1].copy(), cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    value = value.reshape(board.rows + 1, board.cols + 1, -1).mean(axis=-1, dtype=np.float64)
    # Against the neighbours and relative to their brightness, not one threshold: a shadow
    # across the board darkens its white squares below the sunlit black ones.
    padded = np.pad(value, 1, constant_values=np.nan)
    around = np.nanmean([padded[:-2, 1:-1], padded[2:, 1:-1], padded[1:-1, :-2], padded[1:-1, 2:]], axis=0)
    parity = np.where((row + col) % 2 == 0, 1.0, -1.0)
    relative = parity * (value - around) / (value + around + 1.0)
    # Its sign says which squares are the black ones, which depends on how the detector
    # read the board.
    scale = np.median(relative[1:-1, 1:-1])
    return relative / (scale if scale != 0 else 1.0)


def squares_alternate(gray: np.ndarray, corners_px: np.ndarray, board: Board) -> bool:
    """Whether the squares between a checkerboard's detected corners alternate as printed
    (``CAMERA.detect.min_square_contrast``): False for a grid a detector fit partly to
    something else, such as a blurred board's paper edge taken for a row of corners,
    which the mend of outliers cannot see (each corner agrees with its neighbours). A
    grid read a whole square along everywhere still alternates, and passes."""
    # The ring of squares outside the inner corners is not judged: an object over the
    # board's edge hides it while the detector still finds every corner.
    return bool((square_contrast(gray, corners_px, board)[1:-1, 1:-1] >= CAMERA.detect.min_square_contrast).all())


def board_goes_on(gray: np.ndarray, corners_px: np.ndarray, board: Board) -> bool:
    """Whether the checkerboard goes on past the squares around the detected corners:
    along some side, most squares of the next ring out (``CAMERA.detect.goes_on_share``)
    alternate as printed (``CAMERA.detect.min_square_contrast``). Then the grid is a patch
    of a larger board (a 9x6 board given as 7x5, which the detectors find in it), not the
    board. Not all of them: a lens's distortion two squares past the grid, where its
    homography is extrapolated, puts a square or two off."""
    H, _ = cv2.findHomography(board.corners_m()[:, :2], np.asarray(corners_px, np.float64).reshape(-1, 2), 0)
    wider = Board(board.cols + 2, board.rows + 2, board.square_mm)  # its paper does not matter here
    wider_px = cv2.perspectiveTransform(wider.corners_m()[None, :, :2], H)[0]
    ring = square_contrast(gray, wider_px, wider) >= CAMERA.detect.min_square_contrast
    # The sides' end squares are left out: they border the paper.
    sides = (ring[0, 2:-2], ring[-1, 2:-2], ring[2:-2, 0], ring[2:-2, -1])
    return any(side.mean() >= CAMERA.detect.goes_on_share for side in sides)


def _is_the_board(gray: np.ndarray, corners, board: Board) -> bool:
    """Whether a detector's grid is the board: its squares alternate as printed, and it
    is not a patch of a larger board."""
    return squares_alternate(gray, corners, board) and not board_goes_on(gray, corners, board)


def _find_chessboard(gray: np.ndarray, board: Board):
    """Corners (cols * rows, 2) in ``gray`` or None, and which detector found them
    (:func:`_is_the_board`)."""
    pattern = (board.cols, board.rows)
    found, corners = cv2.findChessboardCornersSB(gray, pattern, flags=_SB_FLAGS)
    if found and _is_the_board(gray, corners, board):
        return corners.reshape(-1, 2).astype(np.float64), "sb"
    found, corners = cv2.findChessboardCorners(gray, pattern, flags=_CLASSIC_FLAGS)
    if found and _is_the_board(gray, corners, board):
        return corners.reshape(-1, 2).astype(np.float64), "classic"
    return None, None


def _saddle_points(gray: np.ndarray, count: int) -> tuple[np.ndarray, np.ndarray]:
    """The ``count`` strongest saddle points (local maxima of ``-det(Hessian)``): (k, 2)
    pixels and their strengths. Checkerboard corners, black against white, top the list."""
    blurred = cv2.GaussianBlur(gray.astype(np.float32) / 255.0, (0, 0), 1.5)
    xx = cv2.Sobel(blurred, cv2.CV_32F, 2, 0, ksize=3)
    yy = cv2.Sobel(blurred, cv2.CV_32F, 0, 2, ksize=3)
    xy = cv2.Sobel(blurred, cv2.CV_32F, 1, 1, ksize=3)
    strength = np.maximum(xy * xy - xx * yy, 0)
    peaks = (strength == cv2.dilate(strength, np.ones((5, 5), np.uint8))) & (strength > 0)
    rows, cols = np.nonzero(peaks)
    order = np.argsort(-strength[rows, cols], kind="stable")[:count]
    return np.column_stack([cols[order], rows[order]]).astype(np.float64), strength[rows[order], cols[order]]


def _board_candidates(gray: np.ndarray, board: Board) -> list[tuple[np.ndarray, float]]:
    """Where a board may be: groups of strong saddle points, each as its strongest
    ``cols * rows`` points (k, 2) and their median nearest-neighbor distance, largest total
    strength first.

    Two saddle points join a group when they are closer than three times the nearer of
    their nearest-neighbor distances: a board's corners chain up along its rows and
    columns even when foreshortened 3:1, while stray saddles stay apart."""
    n = board.corner_count
    points, strength = _saddle_points(gray, 4 * n)
    if len(points) < max(n // 2, 2):
        return []
    # Neighbours from a k-d tree, groups as the linked graph's components: a board of
    # many corners gives thousands of points, too many for a dense distance matrix.
    tree = cKDTree(points)
    nearest = tree.query(points, k=2)[0][:, 1]
    balls = tree.query_ball_point(points, 3 * nearest)
    i = np.repeat(np.arange(len(points)), [len(b) for b in balls])
    j = np.concatenate(balls).astype(np.intp)
    keep = (i != j) & (np.linalg.norm(points[i] - points[j], axis=1) <= 3 * np.minimum(nearest[i], nearest[j]))
    links = coo_matrix((np.ones(int(keep.sum())), (i[keep], j[keep])), shape=(len(points), len(points)))
    label = connected_components(links, directed=False)[1]
    groups = []
    # Components in the order of their strongest point, as before (ties in total strength).
    for value in label[np.sort(np.unique(label, return_index=True)[1])]:
        # The group's strongest n: the board's corners, without the paper's edge and the
        # floor's grain that join it (points are sorted by strength).
        members = np.flatnonzero(label == value)[:n]
        if len(members) >= n // 2:
            groups.append((float(strength[members].sum()), points[members], float(np.median(nearest[members]))))
    groups.sort(key=lambda g: -g[0])
    return [(p, spacing) for _, p, spacing in groups[:CAMERA.detect.crop_candidates]]


def _find_in_crops(gray: np.ndarray, small: np.ndarray, scale: float, board: Board):
    """Corners found on crops of ``gray`` around the board candidates seen in ``small``:
    a small board in a big, busy photo is found far more often on its own, enlarged
    twice when its squares are small."""
    settings = CAMERA.detect
    height, width = gray.shape
    for points, spacing in _board_candidates(small, board):
        points = (points + 0.5) / scale - 0.5
        lo, hi = points.min(axis=0), points.max(axis=0)
        margin = settings.crop_margin * (hi - lo).max() + 4
        x0, y0 = np.maximum(np.floor(lo - margin), 0).astype(int)
        x1, y1 = np.minimum(np.ceil(hi + margin), [width - 1, height - 1]).astype(int)
        crop = gray[y0:y1 + 1, x0:x1 + 1]
        zooms = (1, 2) if spacing / scale < settings.crop_zoom_below_px else (1,)
        for zoom in zooms:
            view = crop if zoom == 1 else cv2.resize(crop, None, fx=zoom, fy=zoom, interpolation=cv2.INTER_CUBIC)
            corners, detector = _find_chessboard(view, board)
            if corners is not None:
                return (corners + 0.5) / zoom - 0.5 + [x0, y0], f"{detector} crop"
        corners, detector = _find_rectified(gray, points, board, (x0, y0, x1, y1))
        if corners is not None:
            return corners, f"{detector} rectified"
    return None, None


def _find_rectified(gray: np.ndarray, points: np.ndarray, board: Board, box: tuple[int, int, int, int]):
    """Corners found on an affine view of ``gray`` in which the saddle points ``points``
    (k, 2), a board candidate, spread evenly every way, mapped back to ``gray``; or None.
    The view holds all of ``box`` (x0, y0, x1, y1), the crop around them: cut shorter, a
    larger board (9x6 given as 7x5) shows a 7x5 patch of whole squares, which the
    detectors take for the board.

    A board far away or seen low is squashed along the view and often blurred, and then
    neither detector finds it on the crop; an affine map that makes its saddle points'
    spread round undoes most of the squash. A grid of cols x rows corners a unit apart
    spreads (cols^2 - 1) / 12 and (rows^2 - 1) / 12 along its sides; the view gives each
    direction the mean of the two, at each of ``CAMERA.detect.rectified_spacings_px`` a
    unit in turn (the detectors' luck turns with the scale on boards whose rows are a few
    pixels apart), so its squares come out within a factor of about 1.5 of square
    whatever the squash. The map is symmetric and positive: no mirror.
    """
    center = points.mean(axis=0)
    spread, axes = np.linalg.eigh(np.cov((points - center).T))
    if spread.min() <= 1e-6:
        return None, None
    even = axes @ np.diag(1 / np.sqrt(spread)) @ axes.T * np.sqrt((board.cols ** 2 + board.rows ** 2 - 2) / 24)
    x0, y0, x1, y1 = box
    corners_box = (np.array([[x0, y0], [x1, y0], [x0, y1], [x1, y1]]) - center) @ even.T
    around = int(np.median(gray[y0:y1 + 1, x0:x1 + 1]))  # what the view shows past the crop
    for spacing in CAMERA.detect.rectified_spacings_px:
        A = even * spacing
        lo, hi = corners_box.min(axis=0) * spacing, corners_box.max(axis=0) * spacing
        to_view = np.hstack([A, (-lo - A @ center)[:, None]])
        size = tuple(int(v) for v in np.ceil(hi - lo) + 1)
        if max(size) > CAMERA.detect.rectified_max_px:
            # Saddle points nearly on one line stretch the view across it without bound
            # (one such view took 22 GB in the detector).
            continue
        view = cv2.warpAffine(gray, to_view, size, flags=cv2.INTER_CUBIC, borderMode=cv2.BORDER_CONSTANT,
                              borderValue=around)
        corners, detector = _find_chessboard(view, board)
        if corners is not None:
            back = cv2.invertAffineTransform(to_view)
            return corners @ back[:, :2].T + back[:, 2], detector
    return None, None


def _detect_chessboard(gray: np.ndarray, board: Board) -> BoardDetection | None:
    scale = min(1.0, CAMERA.detect.max_side_px / max(gray.shape))
    small = gray if scale == 1.0 else cv2.resize(gray, None, fx=scale, fy=scale, interpolation=cv2.INTER_AREA)
    corners, detector = _find_chessboard(small, board)
    if corners is not None:
        # Map pixel centers of the small copy back: x_full = (x_small + 0.5) / scale - 0.5.
        corners = (corners + 0.5) / scale - 0.5
    else:
        corners, detector = _find_in_crops(gray, small, scale, board)
        if corners is None:
            return None
    ids = np.arange(board.corner_count)
    return BoardDetection(_refine(gray, corners, ids, board), ids, detector)


def _charuco_detector(board: Board):
    params = cv2.aruco.DetectorParameters()
    params.minMarkerPerimeterRate = 0.01  # markers of a board across the room are small
    charuco = cv2.aruco.CharucoParameters()
    charuco.tryRefineMarkers = True      # look again for missed markers where the board says
    return cv2.aruco.CharucoDetector(charuco_board(board.cols, board.rows), charuco, params)


def _detect_charuco(gray: np.ndarray, board: Board) -> BoardDetection | None:
    # Full resolution: marker bits are small, and reading them is cheap.
    settings = CAMERA.detect
    detector = _charuco_detector(board)
    corners, charuco_ids, _, _ = detector.detectBoard(gray)
    zoom = settings.charuco_zoom
    if (charuco_ids is None or len(charuco_ids) < settings.min_charuco_corners) \
            and max(gray.shape) * zoom <= settings.charuco_zoom_max_px:
        # A far or blurred board's marker bits are a pixel or two: enlarged, their outlines
        # are found. Pixel centers map back as x = (x_big + 0.5) / zoom - 0.5.
        big = cv2.resize(gray, None, fx=zoom, fy=zoom, interpolation=cv2.INTER_CUBIC)
        corners, charuco_ids, _, _ = detector.detectBoard(big)
        if corners is not None:
            corners = (corners + 0.5) / zoom - 0.5
    if charuco_ids is None or len(charuco_ids) < settings.min_charuco_corners \
            or charuco_board(board.cols, board.rows).checkCharucoCornersCollinear(charuco_ids):
        # Markers too small or blurred to read one by one: the board is still a
        # checkerboard, found whole as one, and turned as its markers' pattern says.
        found = _detect_chessboard(gray, board)
        ids = None if found is None else _orient_by_markers(gray, found.corners_px, board)
        return None if ids is None else BoardDetection(found.corners_px, ids, found.detector)
    ids = board.corner_ids(charuco_ids)
    corners = corners.reshape(-1, 2).astype(np.float64)
    order = np.argsort(ids)
    ids, corners = ids[order], corners[order]
    return BoardDetection(_refine(gray, corners, ids, board), ids, "charuco")


def _orient_by_markers(gray: np.ndarray, corners_px: np.ndarray, board: Board) -> np.ndarray | None:
    """Corner ids (cols * rows,) of a ChArUco board whose every corner was found in
    checkerboard order: of the four numberings a checkerboard allows (as read, turned half
    round, either way mirrored), the one under which the middles of the photo's white
    squares correlate best with the printed markers. Blurred markers no detector reads
    still match as a whole. None when no numbering matches them
    (``CAMERA.detect.min_marker_match``): a plain checkerboard."""
    px = 16  # per square: two per marker bit
    template = board.printed_image(px)[::-1].astype(np.float32)  # as Board.image lays it, without the margin
    step = board.square_m / px
    # Template pixel (c, r) -> board meters (x, y): row 0 is board -y, as Board.image draws it.
    meters_from_template = np.array([[step, 0, (0.5 - (board.cols + 1) * px / 2) * step],
                                     [0, step, (0.5 - (board.rows + 1) * px / 2) * step], [0, 0, 1]])
    squares = template.reshape(board.rows + 1, px, board.cols + 1, px).mean(axis=(1, 3))
    edge = (CHARUCO_BITS_PER_SQUARE - CHARUCO_MARKER_BITS) // 2 * px // CHARUCO_BITS_PER_SQUARE
    inner = np.zeros((px, px))
    inner[edge:px - edge, edge:px - edge] = 1
    markers = np.kron(squares > 64, inner) > 0  # the white squares' middles, where markers are printed
    row, col = np.divmod(np.arange(board.corner_count), board.cols)
    numberings = (row * board.cols + col, (board.rows - 1 - row) * board.cols + (board.cols - 1 - col),
                  (board.rows - 1 - row) * board.cols + col, row * board.cols + (board.cols - 1 - col))
    scores = []
    for ids in numberings:
        pixels_from_meters, _ = cv2.findHomography(board.corners_m()[ids][:, :2], corners_px, 0)
        view = cv2.warpPerspective(gray, pixels_from_meters @ meters_from_template, template.shape[::-1],
                                   flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP).astype(np.float32)
        scores.append(np.corrcoef(view[markers], template[markers])[0, 1])
    best = int(np.nanargmax(scores))
    return numberings[best] if scores[best] >= CAMERA.detect.min_marker_match else None


def detect_board(image: np.ndarray, board: Board) -> BoardDetection | None:
    """Find the board's inner corners.

    A checkerboard is looked for in a copy at most ``CAMERA.detect.max_side_px`` on its
    long side (OpenCV's SB detector, then the classic one); when neither finds it, on
    crops around the strongest groups of saddle points, at full resolution and enlarged
    (small, foreshortened boards in large photos). A checkerboard grid whose inner squares
    do not alternate as printed (:func:`squares_alternate`) is passed over. A ChArUco
    board's markers are read at full resolution; any ``CAMERA.detect.min_charuco_corners``
    corners not in a line will do; when fewer are read, the whole board is looked for as a
    checkerboard. Corners are then refined at full resolution to the
    saddle point of the intensity.

    Parameters
    ----------
    image : (h, w) or (h, w, 3) uint8
        Gray or RGB photo. Not modified.
    board : Board

    Returns
    -------
    BoardDetection or None
        None when no board of this kind and size is in the photo.
    """
    gray = _gray(image)
    if board.kind == "charuco":
        return _detect_charuco(gray, board)
    return _detect_chessboard(gray, board)


def suggest_board(image: np.ndarray, board: Board) -> str | None:
    """A ``--board`` value that would find a board in this photo, or None."""
    gray = _gray(image)
    scale = min(1.0, 800 / max(gray.shape))
    small = cv2.resize(gray, None, fx=scale, fy=scale, interpolation=cv2.INTER_AREA) if scale < 1 else gray
    if board.kind == "chessboard":
        # ChArUco markers of Stager's dictionary: the board is a ChArUco one.
        markers = cv2.aruco.ArucoDetector(charuco_board(board.cols, board.rows).getDictionary()).detectMarkers(gray)[1]
        if markers is not None and len(markers) >= 4:
            return f"charuco:{board.cols}x{board.rows}"
    for size in ((board.cols, board.rows),) + _COMMON_SIZES:
        if board.kind == "chessboard" and size in ((board.cols, board.rows), (board.rows, board.cols)):
            continue
        ok, _ = cv2.findChessboardCorners(small, size, flags=_CLASSIC_FLAGS | cv2.CALIB_CB_FAST_CHECK)
        if ok:
            return f"{size[0]}x{size[1]}"
    return None
