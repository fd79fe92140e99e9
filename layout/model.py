"""The frozen model (what does not change while solving) and the state (what does).

The model is a set of NumPy arrays, one group of arrays per constraint kind, named
``<kind>_<field>``. It is produced by :meth:`layout.builder.LayoutBuilder.finalize` and
never modified afterwards; the solver reads it through :meth:`Model.packed`.
"""
from __future__ import annotations

from collections import namedtuple
from dataclasses import dataclass, fields

import numpy as np

# Tuples of arrays handed to the numba kernels, one per constraint kind. Field names
# match the model's attributes minus the kind prefix.
Particles = namedtuple(
    "Particles",
    "role size mass inv_mass body body_offset body_yaw parent collides bounded wall_bound access_depth "
    "mstart mlist radius access_max access_zone",
)
Distances = namedtuple("Distances", "pairs rest mode k0 schedule w_scale")
Lanes = namedtuple("Lanes", "origin item start angle length half_width k0 schedule w_scale")
Centers = namedtuple("Centers", "start members target frame k0 schedule")
Symmetries = namedtuple("Symmetries", "start members focal angle k0 schedule")
Balances = namedtuple("Balances", "start members target k0 schedule")
WallDistances = namedtuple("WallDistances", "item rest mode k0 schedule")
WallOrientations = namedtuple("WallOrientations", "item angle k0 schedule")
Orientations = namedtuple("Orientations", "pairs angle mode k0 schedule")
Stacks = namedtuple("Stacks", "pairs k0 schedule")
Curves = namedtuple("Curves", "group kind params start members spacing anchor_fixed k0 schedule")
Room = namedtuple("Room", "polygon edge_normal reflex clearance grid_origin grid_cell wall planes")


@dataclass(frozen=True, eq=False)
class Model:
    """All particles and constraints of one layout problem, as arrays.

    Particles are items (furniture), groups (a particle standing for several members)
    and obstacles (door and window clearance zones, never moved). Positions are the
    particle's box center in the floor frame (meters, z up); see :mod:`layout.geometry`
    for the yaw and size conventions.
    """

    names: tuple
    kinds: tuple
    particle_role: np.ndarray  # (n,) int8: ITEM, GROUP or OBSTACLE
    particle_size_m: np.ndarray  # (n, 3) width, depth, height
    particle_mass: np.ndarray  # (n,) bounding-box volume in m^3 (groups: sum of members)
    particle_inv_mass: np.ndarray  # (n,) 0 for fixed particles
    particle_body: np.ndarray  # (n,) int32: particle that receives the corrections
    particle_body_offset_m: np.ndarray  # (n, 3) position in the body's frame
    particle_body_yaw_rad: np.ndarray  # (n,) yaw relative to the body
    particle_parent: np.ndarray  # (n,) int32 group, -1 for none
    particle_collides: np.ndarray  # (n,) bool
    particle_bounded: np.ndarray  # (n,) bool: footprint must stay inside the floor
    particle_wall_bound: np.ndarray  # (n,) bool: has a distance-to-wall constraint
    particle_access_depth_m: np.ndarray  # (n, 4) clearance behind, left, front, right
    particle_mstart: np.ndarray  # (n + 1,) CSR offsets into particle_mlist
    particle_mlist: np.ndarray  # rigid members of each body (the body itself excluded)
    particle_radius_m: np.ndarray  # (n,) half diagonal of the footprint
    particle_access_max_m: np.ndarray  # (n,) deepest clearance
    particle_access_zone_m: np.ndarray  # (n, 3) circle round the access boxes, item frame
    #   (center x, y, radius; radius -1 without any): see layout.geometry.access_zones
    particle_init_position_m: np.ndarray  # (n, 3) NaN x/y where the start is random
    particle_init_yaw_rad: np.ndarray  # (n,) NaN where random

    floor_polygon_m: np.ndarray  # (m, 2) counter-clockwise
    floor_edge_normal: np.ndarray  # (m, 2) inward unit normal of edge k -> k+1
    floor_reflex: np.ndarray  # (m,) bool: vertex is an inner (reflex) corner
    floor_edge_wall: np.ndarray  # (m,) bool: edge k -> k+1 is a wall (False: open, e.g. the
    #   photo's edge: items stay inside it but are not put against it)
    floor_clearance_m: np.ndarray  # (gy, gx) distance to the walls that every point of
    #   the grid cell has at least (0 outside or on a wall); a quick inside test
    floor_grid_origin_m: np.ndarray  # (2,) lower-left corner of cell (0, 0)
    floor_grid_cell_m: np.ndarray  # (1,) cell size
    floor_frame_planes: np.ndarray  # (k, 4) n_x, n_y, n_z, d: the space the photo shows is
    #   n . p + d >= 0 (unit n, meters; layout.camera.Camera.frame_planes); (0, 4) without a camera
    camera: object  # layout.camera.Camera or None: the photo's camera, for the criteria it judges by
    camera_rules: object  # layout.camera.CameraRules the planes and the criteria follow (None without)
    wall_height_m: float
    door_segments_m: np.ndarray  # (d, 2, 2) door openings on the walls
    door_particles: np.ndarray  # (d,) int32 obstacle particle of each door's zone
    window_segments_m: np.ndarray  # (w, 2, 2)
    window_particles: np.ndarray  # (w,) int32

    distance_pairs: np.ndarray  # (c, 2) int32
    distance_rest_m: np.ndarray  # (c,)
    distance_mode: np.ndarray  # (c,) int8 EQ/MIN/MAX
    distance_k0: np.ndarray
    distance_schedule: np.ndarray
    distance_w_scale: np.ndarray  # (c, 2) 0 pins that end (focal point with w = 0)

    lane_origin: np.ndarray  # (c,) particle carrying the lane vector
    lane_item: np.ndarray  # (c,) particle kept clear of it
    lane_start_m: np.ndarray  # (c, 2) start of the vector in the origin's frame
    lane_angle_rad: np.ndarray  # (c,) direction relative to the origin's yaw
    lane_length_m: np.ndarray
    lane_half_width_m: np.ndarray
    lane_k0: np.ndarray
    lane_schedule: np.ndarray
    lane_w_scale: np.ndarray  # (c, 2) item, origin

    heat_start: np.ndarray  # (c + 1,) CSR offsets into heat_members
    heat_members: np.ndarray
    heat_target_m: np.ndarray  # (c, 2) in the frame of heat_frame (world if -1)
    heat_frame: np.ndarray
    heat_k0: np.ndarray
    heat_schedule: np.ndarray

    symmetry_start: np.ndarray
    symmetry_members: np.ndarray
    symmetry_focal: np.ndarray
    symmetry_angle_rad: np.ndarray  # axis direction relative to the focal's yaw
    symmetry_k0: np.ndarray
    symmetry_schedule: np.ndarray

    balance_start: np.ndarray
    balance_members: np.ndarray
    balance_target_m: np.ndarray  # (c, 2) the room centroid
    balance_k0: np.ndarray
    balance_schedule: np.ndarray

    wall_distance_item: np.ndarray
    wall_distance_rest_m: np.ndarray  # (c,) wanted distance of the center from the wall
    wall_distance_mode: np.ndarray
    wall_distance_k0: np.ndarray
    wall_distance_schedule: np.ndarray

    wall_orientation_item: np.ndarray
    wall_orientation_angle_rad: np.ndarray  # facing relative to the inward wall normal
    wall_orientation_k0: np.ndarray
    wall_orientation_schedule: np.ndarray

    orientation_pairs: np.ndarray
    orientation_angle_rad: np.ndarray  # (c, 2) desired angle of each end; NaN = free
    orientation_mode: np.ndarray  # FACE or PARALLEL
    orientation_k0: np.ndarray
    orientation_schedule: np.ndarray

    stack_pairs: np.ndarray  # (c, 2) base, top
    stack_k0: np.ndarray
    stack_schedule: np.ndarray

    curve_group: np.ndarray
    curve_kind: np.ndarray  # SEGMENT or ARC
    curve_params: np.ndarray  # (c, 5) segment: ax ay bx by 0; arc: cx cy r a0 a1
    curve_start: np.ndarray
    curve_members: np.ndarray
    curve_spacing_m: np.ndarray  # (c,) 0 = no spacing constraint between neighbours
    curve_anchor_fixed: np.ndarray  # (c,) bool: curve point has infinite mass (paper)
    curve_k0: np.ndarray
    curve_schedule: np.ndarray

    @property
    def n(self) -> int:
        return len(self.names)

    @property
    def items(self) -> np.ndarray:
        """Indices of the furniture items (not groups or obstacles)."""
        return np.flatnonzero(self.particle_role == 0)

    def packed(self):
        """Named tuples of arrays, the argument form of the numba kernels."""
        cached = self.__dict__.get("_packed")
        if cached is None:
            get = lambda prefix, cls: cls(  # noqa: E731
                *[getattr(self, _attr(self, prefix, f)) for f in cls._fields]
            )
            cached = (
                get("particle", Particles),
                get("distance", Distances),
                get("lane", Lanes),
                get("heat", Centers),
                get("symmetry", Symmetries),
                get("balance", Balances),
                get("wall_distance", WallDistances),
                get("wall_orientation", WallOrientations),
                get("orientation", Orientations),
                get("stack", Stacks),
                get("curve", Curves),
                Room(self.floor_polygon_m, self.floor_edge_normal, self.floor_reflex, self.floor_clearance_m,
                     self.floor_grid_origin_m, self.floor_grid_cell_m, self.floor_edge_wall,
                     self.floor_frame_planes),
            )
            object.__setattr__(self, "_packed", cached)
        return cached

    def counts(self) -> dict:
        """Number of constraints of each static kind."""
        return {
            "distance": len(self.distance_rest_m),
            "lane": len(self.lane_origin),
            "heat": len(self.heat_frame),
            "symmetry": len(self.symmetry_focal),
            "balance": len(self.balance_target_m),
            "wall_distance": len(self.wall_distance_item),
            "wall_orientation": len(self.wall_orientation_item),
            "orientation": len(self.orientation_mode),
            "stack": len(self.stack_k0),
            "curve": len(self.curve_group),
        }


def _attr(model, prefix, name):
    """Model attribute for a packed field, allowing the unit suffixes used in the model."""
    for candidate in (f"{prefix}_{name}", f"{prefix}_{name}_m", f"{prefix}_{name}_rad"):
        if candidate in _FIELD_NAMES:
            return candidate
    raise AttributeError(f"model has no field for {prefix}.{name}")


_FIELD_NAMES = {f.name for f in fields(Model)}


@dataclass
class State:
    """What changes while solving: particle poses.

    Attributes
    ----------
    position_m : (n, 3) float64
        Particle centers. Rigid-group members are kept in sync with their body.
    yaw_rad : (n,) float64
        Facing direction of each particle.
    """

    position_m: np.ndarray
    yaw_rad: np.ndarray

    def copy(self) -> "State":
        return State(self.position_m.copy(), self.yaw_rad.copy())
