"""The calibration board: a ChArUco board (OpenCV's ``aruco`` module), its pattern and its detection.

A ChArUco board is a chessboard whose white squares hold ArUco markers: each inner chessboard
corner is identified by the markers around it, so a partly hidden or steeply tilted board still
gives corners that are known points of the board. ``cv2.aruco.CharucoDetector`` finds the markers,
interpolates the corners and refines them below a pixel (``cornerSubPix``).

The board frame is OpenCV's: origin at the pattern's first outer corner, x along ``squares_x``,
y along ``squares_y``, z into the board; the printed face is seen from the -z side. Lengths in
metres.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

from bt_arrange.errors import PlanError
from bt_arrange.geometry import FloatArray

#: The fewest interpolated corners a view must have to count: fewer, and its pose is too weak.
MIN_CORNERS = 8


@dataclass(frozen=True)
class BoardObservation:
    """The ChArUco corners one image shows: pixel positions, their ids and the board points they are."""

    #: Corner positions in the image (N x 2, pixel-centre convention, distorted: as imaged).
    image_points_px: FloatArray
    #: The corners' ids (N).
    ids: NDArray[np.int32]
    #: The same corners in the board frame (N x 3, metres, z = 0).
    board_points_m: FloatArray

    @property
    def count(self) -> int:
        """How many corners were found."""
        return len(self.ids)


@dataclass(frozen=True)
class CharucoBoard:
    """A ChArUco board: ``squares_x`` by ``squares_y`` squares of ``square_m``, markers of ``marker_m``.

    The default is 7 x 5 squares of 30 mm with 22 mm markers of ``DICT_4X4_50``: 210 x 150 mm,
    24 inner corners, large enough to cover a good part of the top camera's view at 40 cm and small
    enough for the UR5 to tilt it by 25 degrees without hitting anything.
    """

    squares_x: int = 7
    squares_y: int = 5
    square_m: float = 0.030
    marker_m: float = 0.022
    dictionary: str = "DICT_4X4_50"
    #: White margin around the pattern on the plate (the outer markers need a quiet zone).
    margin_m: float = 0.010
    #: The id of the board's first marker: two boards of one dictionary with disjoint ids are never
    #: taken for each other (the table sheet's markers follow the flange board's).
    first_marker_id: int = 0

    def __post_init__(self) -> None:
        if self.squares_x < 3 or self.squares_y < 3:
            raise PlanError(f"a ChArUco board needs at least 3 x 3 squares, got {self.squares_x} x {self.squares_y}")
        if not 0.0 < self.marker_m < self.square_m:
            raise PlanError(f"the markers ({self.marker_m} m) must be smaller than the squares ({self.square_m} m)")
        if not hasattr(cv2.aruco, self.dictionary):
            raise PlanError(f"unknown ArUco dictionary {self.dictionary!r}")
        markers = (self.squares_x * self.squares_y) // 2
        size = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, self.dictionary)).bytesList.shape[0]
        if self.first_marker_id < 0 or self.first_marker_id + markers > size:
            raise PlanError(
                f"markers {self.first_marker_id} to {self.first_marker_id + markers - 1} do not fit in "
                f"{self.dictionary} ({size} markers)"
            )

    @property
    def size_m(self) -> tuple[float, float]:
        """The pattern's width and height (x, y), without the margin."""
        return self.squares_x * self.square_m, self.squares_y * self.square_m

    @property
    def plate_size_m(self) -> tuple[float, float]:
        """The plate's width and height (x, y): the pattern and its margin."""
        width, height = self.size_m
        return width + 2 * self.margin_m, height + 2 * self.margin_m

    @property
    def centre_m(self) -> FloatArray:
        """The pattern's centre in the board frame."""
        width, height = self.size_m
        return np.array([width / 2, height / 2, 0.0])

    @property
    def corner_count(self) -> int:
        """How many inner corners the board has."""
        return (self.squares_x - 1) * (self.squares_y - 1)

    def opencv_board(self) -> cv2.aruco.CharucoBoard:
        """The OpenCV board object."""
        dictionary = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, self.dictionary))
        ids = np.arange(self.first_marker_id, self.first_marker_id + (self.squares_x * self.squares_y) // 2)
        return cv2.aruco.CharucoBoard(
            (self.squares_x, self.squares_y), self.square_m, self.marker_m, dictionary, ids.astype(np.int32)
        )

    def corners_m(self) -> FloatArray:
        """Every inner corner in the board frame, by id (N x 3)."""
        return np.asarray(self.opencv_board().getChessboardCorners(), dtype=np.float64).reshape(-1, 3)

    def plate_image(self, px_per_m: float = 8000.0) -> NDArray[np.uint8]:
        """The plate as a grey image (pattern and white margin), ``px_per_m`` pixels per metre: a texture."""
        width, height = self.size_m
        pattern = self.opencv_board().generateImage(
            (round(width * px_per_m), round(height * px_per_m)), marginSize=0, borderBits=1
        )
        margin = round(self.margin_m * px_per_m)
        return np.asarray(cv2.copyMakeBorder(pattern, margin, margin, margin, margin, cv2.BORDER_CONSTANT, value=255))

    def detect(self, rgb: NDArray[np.uint8]) -> BoardObservation | None:
        """The board's corners in an RGB image, or None when fewer than ``MIN_CORNERS`` are found."""
        gray = cv2.cvtColor(np.ascontiguousarray(rgb), cv2.COLOR_RGB2GRAY) if rgb.ndim == 3 else rgb
        corners, ids, _, _ = cv2.aruco.CharucoDetector(self.opencv_board()).detectBoard(gray)
        if corners is None or ids is None or len(ids) < MIN_CORNERS:
            return None
        ids = np.asarray(ids, dtype=np.int32).reshape(-1)
        return BoardObservation(np.asarray(corners, dtype=np.float64).reshape(-1, 2), ids, self.corners_m()[ids].copy())


#: The table sheet: a ChArUco board printed on a flat plate and laid on the table top by hand, where
#: the parts lie (``bt_arrange.calibration.procedure``). 12 x 9 squares of 40 mm (480 x 360 mm, about
#: A2) with 30 mm markers 17 to 70 of ``DICT_4X4_100``: the same family as the flange board's (whose
#: markers are 0 to 16, ``DICT_4X4_50`` being the first 50 of it), so neither is taken for the other.
TABLE_SHEET = CharucoBoard(
    squares_x=12, squares_y=9, square_m=0.040, marker_m=0.030, dictionary="DICT_4X4_100", first_marker_id=17
)
#: The sheet's thickness (a print on a 3 mm composite plate, which keeps it flat): its face lies this
#: far above the table top.
TABLE_SHEET_THICKNESS_M = 0.003
