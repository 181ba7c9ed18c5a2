"""The top view's pieces that make it height first, on images built here with NumPy.

A thin part going on from an object (``thin_parts``), colour that does or does not line up
with the depth (``registration``), the table's clear rectangle (``table_plane``): each on a
synthetic image whose answer is known by construction, each checked both ways.
"""

import cv2
import numpy as np
import pytest

from comgrasp_pin.camera import PinholeCamera
from comgrasp_pin.errors import (
    AmbiguousObjectError,
    ColourDepthMismatchError,
    UntrustedImageError,
)
from comgrasp_pin.perception.top_view.registration import check_registered, cover_by_shift
from comgrasp_pin.perception.top_view.rod_pieces import check_not_broken, join_pieces
from comgrasp_pin.perception.top_view.table_plane import fit_table_plane
from comgrasp_pin.perception.top_view.thin_parts import (
    TableStretches,
    check_no_hidden_part,
    check_no_thin_part,
    robot_parts,
)

PX_PER_M = 500.0  # 2 mm pixels
H, W = 300, 400


def _head_and_handle(handle_height: float, noise: float, seed: int = 0):
    """(heights (m), the head's mask, the table's pixels): a 4 x 8 cm head 3 cm high and a
    handle 5 px wide, 20 cm long, ``handle_height`` high, going right from it, on a table
    with white noise ``noise`` (m)."""
    heights = np.random.default_rng(seed).normal(0.0, noise, (H, W))
    head = np.zeros((H, W), bool)
    head[130:170, 100:120] = True
    heights[head] += 0.03
    handle = np.zeros((H, W), bool)
    handle[148:153, 120:220] = True
    heights[handle] += handle_height
    table = ~cv2.dilate((head | handle).astype(np.uint8), np.ones((9, 9), np.uint8)).astype(bool)
    return heights, head, table


def test_a_handle_below_the_threshold_going_on_from_a_head_is_refused():
    """A 7 mm handle in 4 mm of noise (under 2 stds a pixel, lost to any threshold) stands
    far above a 16 cm stretch's noise (4 mm / sqrt(80 px) = 0.45 mm): refused, the message
    giving its direction (about 0 deg: along +u) and its mean height."""
    heights, head, table = _head_and_handle(0.007, 0.004)
    with pytest.raises(UntrustedImageError, match=r"at [0-3] deg .* [5-9]\.\d mm high"):
        check_no_thin_part(heights, head, table, PX_PER_M)


@pytest.mark.parametrize("handle_height", [0.0, 0.002])
def test_no_handle_or_one_lower_than_an_object_is_not_a_thin_part(handle_height):
    """The same head alone, or with a 2 mm cord (lower than the top view's least object
    height, 3 mm, however long): nothing goes on from it."""
    heights, head, table = _head_and_handle(handle_height, 0.004, seed=1)
    check_no_thin_part(heights, head, table, PX_PER_M)


def test_the_robots_fingers_beyond_bare_table_are_not_a_thin_part():
    """A head's end, 4 cm of bare table, then a finger 2 cm high reaching the image's edge,
    its fringe fading from 2 mm, in 0.4 mm of noise: a 16 cm stretch's mean would stand far
    above its noise. As the top view hands it in (only what is too low to stand, the
    robot's parts and their fringe left out: ``robot_parts``), no thin part."""
    heights, head, table = _head_and_handle(0.0, 0.0004, seed=2)
    finger = np.zeros((H, W), bool)
    finger[130:, 140:170] = True  # from 4 cm beyond the head (20 px at 2 mm) to the edge
    heights[finger] += 0.02
    fringe = cv2.dilate(finger.astype(np.uint8), np.ones((7, 7), np.uint8)).astype(bool)
    heights[fringe & ~finger] += 0.002
    table &= ~cv2.dilate(finger.astype(np.uint8), np.ones((9, 9), np.uint8)).astype(bool)
    low = ~robot_parts(heights, 0.003, 1 / PX_PER_M) & ~(heights > 0.003)
    check_no_thin_part(np.where(low, heights, np.nan), head, table, PX_PER_M)
    with pytest.raises(UntrustedImageError):  # handed in whole, the finger is counted
        check_no_thin_part(heights, head, table, PX_PER_M)


def test_a_handle_fading_into_the_table_is_refused():
    """A handle whose height in the depth falls from 2.5 mm at the head to nothing over
    6 cm, in 0.4 mm of noise (a structured-light camera's mallet): joined to the head, about
    1.4 mm high on average, many times its noise: refused."""
    heights, head, table = _head_and_handle(0.0, 0.0004, seed=3)
    fade = np.clip(np.linspace(0.0025, -0.0005, 30), 0, None)  # over 30 px, 6 cm
    heights[148:153, 120:150] += fade[None, :]
    table[140:160, 115:160] = False
    with pytest.raises(UntrustedImageError, match=r"at (\d|35\d) deg .* joined to it"):
        check_no_thin_part(heights, head, table, PX_PER_M)


@pytest.mark.parametrize(
    "length, width, noise, refused",
    [
        (0.09, 0.04, 0.012, True),  # a mallet's head in a depth a 5 mm handle is lost in
        (0.09, 0.04, 0.004, False),  # the same head where a 3 mm part would show
        (0.28, 0.04, 0.012, False),  # a rod's shape (7 times as long as wide)
        (0.13, 0.04, 0.012, False),  # over 3 times: a rod's shape
    ],
)
def test_a_short_object_in_a_depth_too_noisy_for_a_handle_is_refused(length, width, noise,
                                                                     refused):  # fmt: skip
    """In white noise of std s, a 16 cm ray (80 px at 2 mm) has a mean of noise
    s / sqrt(80): 12 mm gives 1.34 mm, so a part lower than 4 of them (5.4 mm) is not found,
    above the least height of an object (3 mm): an object under 3 times as long as wide may
    be a head whose handle is lost, and the message gives the 5.4 mm. 4 mm of noise (a part
    of 1.8 mm would be found) or a rod's shape pass."""
    heights = np.random.default_rng(4).normal(0.0, noise, (H, W))
    table = np.ones((H, W), bool)
    if not refused:
        check_no_hidden_part(length, width, heights, table, PX_PER_M)
        return
    least = 4 * noise / np.sqrt(0.16 * PX_PER_M)
    with pytest.raises(UntrustedImageError, match=r"9 cm long and 4\.0 cm wide") as err:
        check_no_hidden_part(length, width, heights, table, PX_PER_M)
    shown = float(str(err.value).split("lower than ")[1].split(" mm")[0])
    assert shown == pytest.approx(1e3 * least, rel=0.08)


def _rod_mask(du: int = 0, dv: int = 0) -> np.ndarray:
    mask = np.zeros((H, W), bool)
    mask[140 + dv : 152 + dv, 80 + du : 300 + du] = True  # a rod 12 px wide along u
    return mask


@pytest.mark.parametrize("shift", [(0, 6), (10, 0), (-7, 9), (0, 25)])
def test_colour_moved_against_the_depth_is_found_and_refused(shift):
    """The colour's mask of the rod moved by (du, dv) px: the least of the best shifts is
    within a pixel of that move (the depth's core, eroded by a pixel, fits a pixel either
    way), and the pair is refused where the move is across the rod; along its own axis a
    move of 10 px still covers 95 %, which is why the refusal asks for a gain."""
    depth_mask, colour_mask = _rod_mask(), _rod_mask(*shift)
    core = cv2.erode(depth_mask.astype(np.uint8), np.ones((3, 3), np.uint8)).astype(bool)
    _, best, found = cover_by_shift(colour_mask, core)
    assert np.abs(found - np.array(shift)).max() <= 1 and best == pytest.approx(1.0)
    if abs(shift[1]) > 2:  # across the rod: most of it is lost where it is
        with pytest.raises(ColourDepthMismatchError, match="do not line up"):
            check_registered(colour_mask, depth_mask)


def test_registered_colour_helps_and_a_table_coloured_rod_does_not():
    """The same mask in colour and depth: registered (True); a colour that marks nothing
    of the object (a rod of the table's colour): no help (False), not a refusal."""
    assert check_registered(_rod_mask(), _rod_mask()) is True
    elsewhere = np.zeros((H, W), bool)
    elsewhere[20:40, 20:40] = True  # a mark far from the rod
    assert check_registered(elsewhere, _rod_mask()) is False


def test_the_clear_rectangle_leaves_out_what_reaches_into_the_view():
    """A camera 1 m above a table (z-depth 1 m everywhere), with an arm reaching in from
    the image's foot (nearer, 0.6 m) over its lower quarter: the pick area, in the table's
    frame (x to the image's right, y to its top), lies above the arm, within the table in
    view, and 2 cm inside it."""
    camera = PinholeCamera(fx=500.0, fy=500.0, cx=W / 2 - 0.5, cy=H / 2 - 0.5, width=W, height=H)
    depth = np.ones((H, W))
    depth[int(0.75 * H) :, 100:300] = 0.6  # the arm at the foot of the image
    T_table_cam, (x0, x1, y0, y1) = fit_table_plane(depth, camera)
    half_w, half_h = 0.5 * W / 500.0, 0.5 * H / 500.0  # the table in view (m) at 1 m
    assert abs(T_table_cam[2, 3] - 1.0) < 1e-6  # the camera 1 m above the plane
    # the largest rectangle is the whole width above the arm (0.8 x 0.45 m), not a side
    # strip beside it (0.2 x 0.6 m): from the arm's edge (image row 0.75 H: y = -0.15 m) up
    arm_edge_y = -(0.75 * H - H / 2) / 500.0
    assert x0 == pytest.approx(-half_w + 0.02, abs=0.012)
    assert x1 == pytest.approx(half_w - 0.02, abs=0.012)
    assert y0 == pytest.approx(arm_edge_y + 0.02, abs=0.012)
    assert y1 == pytest.approx(half_h - 0.02, abs=0.012)


@pytest.mark.parametrize("noise", [0.0, 0.004])
def test_the_table_is_found_above_a_floor_the_camera_sees_more_of(noise):
    """A camera 1.25 m above a 0.8 x 0.5 m table whose floor, 0.75 m below it, fills the
    rest of the view (70 % of the pixels): the fitted plane is the table's (the camera
    1.25 m above it), not the floor's, and the pick area lies within the table; the same
    under 4 mm of white depth noise, which the plane's inlier band follows."""
    camera = PinholeCamera(fx=600.0, fy=600.0, cx=319.5, cy=239.5, width=640, height=480)
    v, u = np.mgrid[0:480, 0:640]
    on_table = (np.abs(u - 319.5) < 0.4 * 600 / 1.25) & (np.abs(v - 239.5) < 0.25 * 600 / 1.25)
    depth = np.where(on_table, 1.25, 2.0)
    depth = depth + np.random.default_rng(4).normal(0.0, noise, depth.shape)
    T_table_cam, (x0, x1, y0, y1) = fit_table_plane(depth, camera)
    assert abs(T_table_cam[2, 3] - 1.25) < 0.005
    assert -0.4 < x0 < x1 < 0.4 and -0.25 < y0 < y1 < 0.25
    assert x1 - x0 > 0.65 and y1 - y0 > 0.38


def _broken_rod(gap_height: float):
    """(points (H, W, 3) on a 2 mm grid, standing (above 11 mm), the first piece): a rod
    20 mm high along x, broken at x = 0.2 m by a 2 cm gap ``gap_height`` high."""
    v, u = np.mgrid[0:H, 0:W]
    points = np.dstack([u * 0.002, v * 0.002, np.zeros((H, W))])
    rod = (np.abs(v - 150) <= 4) & (u >= 40) & (u < 300)
    points[..., 2] = np.where(rod, 0.02, 0.0)
    points[..., 2][rod & (u >= 100) & (u < 110)] = gap_height
    standing = points[..., 2] > 0.011
    return points, standing, standing & (u < 100)


def test_a_rod_broken_by_the_noise_is_joined_and_two_rods_end_to_end_are_not():
    """The depth's threshold lost a rod's pixels over 2 cm where they stand 10.5 mm (the
    rod's 20 mm in noise): one rod, joined through the gap (half the rod's height or more).
    The same two pieces with bare table between them: two objects, not joined."""
    points, standing, first = _broken_rod(0.0105)
    joined, bridge, _ = join_pieces(points, standing, first, 0.0)
    assert joined[150, 200] and joined[150, 105] and bridge[150, 105]
    points, standing, first = _broken_rod(0.0)
    apart, bridge, gaps = join_pieces(points, standing, first, 0.0)
    assert not apart[150, 200] and not bridge.any()
    # named as what it may be, with the gap's length (between the pixels' centres, u = 99
    # and 110 on the 2 mm grid) and height, not as any other object
    with pytest.raises(AmbiguousObjectError, match="on the rod's axis 22 mm beyond its end.*"
                                                   "stands 0.0 mm on average"):  # fmt: skip
        check_not_broken(standing, apart, gaps)


def test_a_piece_on_the_axis_is_named_and_other_objects_are_counted_first():
    """A 2 cm gap standing 8 mm, under half the rod's 20 mm: not joined, and named; a box
    elsewhere in the area is the reason to refuse first (``standing.segment``'s order)."""
    points, standing, first = _broken_rod(0.008)
    mask, _, gaps = join_pieces(points, standing, first, 0.0)
    assert len(gaps) == 1 and gaps[0].length == pytest.approx(0.022)
    assert gaps[0].mean == pytest.approx(0.008) and gaps[0].least == pytest.approx(0.01)
    with pytest.raises(AmbiguousObjectError, match="stands 8.0 mm on average, short of the "
                                                   "10.0 mm"):  # fmt: skip
        check_not_broken(standing, mask, gaps)
    small = standing & ~(gaps[0].piece & (np.arange(W) >= 114)[None, :])  # 36 px of it seen
    check_not_broken(small, mask, gaps)  # too small to count as an object: no refusal


@pytest.mark.parametrize("length_px", [1, 5, 12, 37, 120, 401])
def test_a_stretchs_noise_is_that_of_every_whole_strip_on_the_table(length_px):
    heights, _, table = _head_and_handle(0.005, 0.002, seed=3)
    heights[np.random.default_rng(4).random((H, W)) < 0.02] = np.nan  # lost pixels
    seen = table & np.isfinite(heights)
    h = np.where(seen, heights, 0.0).astype(np.float32).astype(float)
    means = []
    for hh, ss in ((h, seen), (h.T, seen.T)):  # every strip along rows, then columns
        if length_px > hh.shape[1]:
            continue
        windows = np.lib.stride_tricks.sliding_window_view(hh, length_px, axis=1)
        whole = np.lib.stride_tricks.sliding_window_view(ss, length_px, axis=1).all(axis=2)
        means.append(windows.sum(axis=2)[whole] / length_px)
    values = np.concatenate(means) if means else np.zeros(0)
    noise = TableStretches(heights, table).noise(length_px)
    if len(values) <= 100:
        assert np.isnan(noise)
    else:
        expected = 1.4826 * np.median(np.abs(values - np.median(values)))
        assert noise == pytest.approx(expected, rel=1e-9)
