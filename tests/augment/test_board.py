"""The board (augment.camera.board): the ChArUco pattern is OpenCV's, and its corner numbers land
where the board frame says, on the printed page and in the texture the photographer uses."""
from __future__ import annotations

import cv2
import numpy as np
import pytest

from augment.camera.board import CHARUCO_DICTIONARY, Board, charuco_board


@pytest.mark.parametrize("cols, rows, px", [(7, 5, 32), (5, 3, 64), (9, 6, 40)])
def test_charuco_page_is_opencvs_pattern(cols, rows, px):
    """OpenCV's own generator draws the same page (40 px per square rounds bit edges the
    way OpenCV does)."""
    board = Board(cols, rows, 30, kind="charuco")
    reference = charuco_board(cols, rows).generateImage(((cols + 1) * px, (rows + 1) * px), marginSize=0,
                                                         borderBits=1)
    np.testing.assert_array_equal(board.printed_image(px), reference)


def test_checkerboard_image_is_unchanged_and_charuco_texture_is_the_page_upside_down():
    plain = Board()
    squares = plain.printed_image(8)
    # Top-left square black, alternating.
    assert squares[0, 0] == 0 and squares[0, 8] == 255 and squares[8, 0] == 255
    pad_y, pad_x = (np.array(plain.image(8).shape) - squares.shape) // 2
    np.testing.assert_array_equal(plain.image(8)[pad_y:pad_y + squares.shape[0], pad_x:pad_x + squares.shape[1]],
                                  squares)
    board = Board(kind="charuco")
    page = board.printed_image(16)
    texture = board.image(16)
    pad_y, pad_x = (np.array(texture.shape) - page.shape) // 2
    np.testing.assert_array_equal(texture[pad_y:pad_y + page.shape[0], pad_x:pad_x + page.shape[1]], page[::-1])


def _page_px(board: Board, corners_m: np.ndarray, px: int) -> np.ndarray:
    """Where board-frame points fall on the printed page image (x right, y up the page)."""
    x = corners_m[:, 0] / board.square_m * px + (board.cols + 1) * px / 2 - 0.5
    y = (board.rows + 1) * px / 2 - corners_m[:, 1] / board.square_m * px - 0.5
    return np.column_stack([x, y])


def test_charuco_corner_ids_follow_the_board_frame():
    """OpenCV's detector reads the printed page; its ids, through Board.corner_ids, are the
    corners of Board.corners_m at the places the board frame puts them (y up the page)."""
    board = Board(7, 5, 45, kind="charuco")
    px = 40
    page = np.pad(board.printed_image(px), px, constant_values=255)
    corners, charuco_ids, _, _ = cv2.aruco.CharucoDetector(charuco_board(7, 5)).detectBoard(page)
    assert len(charuco_ids) == board.corner_count
    ids = board.corner_ids(charuco_ids)
    assert sorted(ids) == list(range(board.corner_count))
    expected = _page_px(board, board.corners_m()[ids], px) + px
    np.testing.assert_allclose(corners.reshape(-1, 2), expected, atol=0.5)
    # Corner 0 is at -x, -y: the bottom-left of the printed page.
    assert board.corner_ids([board.cols * (board.rows - 1)])[0] == 0


def test_board_kinds_and_their_limits():
    assert Board().kind == "chessboard" and Board().spec == "7x5"
    assert Board(kind="charuco").spec == "charuco:7x5"
    assert CHARUCO_DICTIONARY in Board(kind="charuco").describe()
    assert Board(kind="charuco").marker_count == 24
    with pytest.raises(ValueError, match="'aruco'.*chessboard, charuco"):
        Board(kind="aruco")
    # 12 x 9 squares hold 54 markers: more than DICT_4X4_50 has.
    with pytest.raises(ValueError, match=r"11x8 needs 54 markers.*DICT_4X4_50 has 50"):
        Board(11, 8, 20, kind="charuco")
    assert Board(9, 6, 20, kind="charuco").marker_count == 35
