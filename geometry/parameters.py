"""Parameters of the slip-joint cones and their case files (SI units).

Conventions
-----------
* z axis vertical, up; the MP bottom is at z = 0 (global frame).
* A part is a thin-walled tube: a conical part plus a straight cylindrical part,
  coaxial with the z axis. Heights ``z`` passed to a part's radius functions are
  *part-local*: measured from the part's lower end.
* ``thickness`` is the radial (horizontal) wall thickness: inner radius = outer
  radius - thickness on every horizontal section, so the inner cone has the same
  half-angle as the outer one and the wall is continuous at the cone/straight
  junction. (The thickness normal to the cone wall is ``thickness * cos(alpha)``,
  6 um less than 6 mm at 1 deg.)
* Primary inputs: half-angle, outer diameter at the cone bottom, cone length
  (axial), straight length, thickness. The cone-top diameter is derived; it may
  also be given, and is then only accepted if consistent.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import numpy as np
import numpy.typing as npt

from common.case import construct, read_case
from common.material import Material

#: accepted mismatch of a given cone-top diameter, relative to the bottom diameter
TOP_DIAMETER_RTOL = 1e-3


@dataclass(frozen=True)
class ConePart:
    """One part (MP or TP): a conical tube plus a straight tube.

    Lengths in m, angle in degrees. ``straight_part`` says whether the straight
    tube is below the cone (MP) or above it (TP); its outer diameter equals the
    cone's outer diameter where they join.
    """

    half_angle_deg: float  #: cone half-angle [deg]
    bottom_outer_diameter: float  #: outer diameter at the cone's bottom [m]
    cone_length: float  #: axial length of the cone [m]
    straight_length: float  #: axial length of the straight part [m]
    thickness: float  #: radial wall thickness [m]
    top_outer_diameter: float | None = None  #: optional check value [m]
    straight_part: Literal["below", "above"] = "below"

    def __post_init__(self) -> None:
        if not 0.0 <= self.half_angle_deg < 45.0:
            raise ValueError(f"half_angle_deg must lie in [0, 45) deg, got {self.half_angle_deg}")
        for name in ("bottom_outer_diameter", "cone_length", "thickness"):
            if not getattr(self, name) > 0:
                raise ValueError(f"{name} must be positive, got {getattr(self, name)} m")
        if not self.straight_length >= 0:
            raise ValueError(f"straight_length must be >= 0, got {self.straight_length} m")
        if self.straight_part not in ("below", "above"):
            raise ValueError(
                f"straight_part must be 'below' or 'above', got {self.straight_part!r}"
            )
        if not self.thickness < self.cone_top_outer_radius:
            raise ValueError(
                f"thickness {self.thickness} m must be smaller than the cone-top outer radius "
                f"{self.cone_top_outer_radius:.6g} m (cone_length too long for this angle?)"
            )
        if self.top_outer_diameter is not None:
            derived = 2.0 * self.cone_top_outer_radius
            if (
                abs(self.top_outer_diameter - derived)
                > TOP_DIAMETER_RTOL * self.bottom_outer_diameter
            ):
                implied = self.implied_half_angle_deg(self.top_outer_diameter)
                raise ValueError(
                    f"top_outer_diameter {self.top_outer_diameter} m is inconsistent with "
                    f"half_angle_deg {self.half_angle_deg} deg over cone_length "
                    f"{self.cone_length} m from bottom_outer_diameter "
                    f"{self.bottom_outer_diameter} m, which give {derived:.4f} m; the given "
                    f"diameters imply a half-angle of {implied:.2f} deg. "
                    "Angles, bottom diameters, lengths and thickness are primary: drop "
                    "top_outer_diameter or make it consistent."
                )

    @classmethod
    def from_dict(cls, data: dict[str, Any], name: str = "part") -> ConePart:
        """Build from a plain dict (e.g. a TOML table); errors name the table ``name``."""
        return construct(cls, data, name)

    # --- derived geometry -------------------------------------------------------------
    @property
    def half_angle(self) -> float:
        """Cone half-angle [rad]."""
        return math.radians(self.half_angle_deg)

    @property
    def total_length(self) -> float:
        """Axial length of cone plus straight part [m]."""
        return self.cone_length + self.straight_length

    @property
    def cone_bottom_z(self) -> float:
        """Part-local height of the cone's bottom [m]."""
        return self.straight_length if self.straight_part == "below" else 0.0

    @property
    def cone_top_z(self) -> float:
        """Part-local height of the cone's top [m]."""
        return self.cone_bottom_z + self.cone_length

    @property
    def cone_bottom_outer_radius(self) -> float:
        """Outer radius at the cone's bottom [m]."""
        return 0.5 * self.bottom_outer_diameter

    @property
    def cone_top_outer_radius(self) -> float:
        """Outer radius at the cone's top, derived from angle and length [m]."""
        return self.cone_bottom_outer_radius - self.cone_length * math.tan(self.half_angle)

    @property
    def derived_top_outer_diameter(self) -> float:
        """Outer diameter at the cone's top [m]."""
        return 2.0 * self.cone_top_outer_radius

    def implied_half_angle_deg(self, top_outer_diameter: float) -> float:
        """Half-angle [deg] that a cone-top outer diameter would imply."""
        return math.degrees(
            math.atan((self.bottom_outer_diameter - top_outer_diameter) / (2 * self.cone_length))
        )

    def outer_radius(self, z: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """Outer radius [m] at part-local height(s) ``z`` [m] (held constant outside)."""
        s = np.clip(np.asarray(z, dtype=np.float64) - self.cone_bottom_z, 0.0, self.cone_length)
        return self.cone_bottom_outer_radius - s * math.tan(self.half_angle)

    def inner_radius(self, z: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """Inner radius [m] at part-local height(s) ``z`` [m]."""
        return self.outer_radius(z) - self.thickness

    def profile_heights(self) -> tuple[float, ...]:
        """Part-local heights where the profile changes (ends and junction) [m]."""
        if self.straight_length == 0.0:
            return (0.0, self.cone_length)
        return (
            0.0,
            self.cone_bottom_z if self.straight_part == "below" else self.cone_top_z,
            self.total_length,
        )

    @property
    def volume(self) -> float:
        """Exact material volume of the thick-walled conical + straight tube [m^3]."""
        r1, r2, t = self.cone_bottom_outer_radius, self.cone_top_outer_radius, self.thickness
        rs = r1 if self.straight_part == "below" else r2

        def frustum(a: float, b: float) -> float:  # solid frustum of radii a, b
            return math.pi * self.cone_length / 3.0 * (a * a + a * b + b * b)

        cone = frustum(r1, r2) - frustum(r1 - t, r2 - t)
        straight = math.pi * (rs**2 - (rs - t) ** 2) * self.straight_length
        return cone + straight

    def mass(self, material: Material) -> float:
        """Mass [kg] for the material's density."""
        return material.rho * self.volume

    def _frustum_lateral_area(self, r1: float, r2: float) -> float:
        return math.pi * (r1 + r2) * self.cone_length / math.cos(self.half_angle)

    @property
    def outer_cone_area(self) -> float:
        """Exact area of the outer conical surface [m^2]."""
        return self._frustum_lateral_area(self.cone_bottom_outer_radius, self.cone_top_outer_radius)

    @property
    def inner_cone_area(self) -> float:
        """Exact area of the inner conical surface [m^2]."""
        t = self.thickness
        return self._frustum_lateral_area(
            self.cone_bottom_outer_radius - t, self.cone_top_outer_radius - t
        )


@dataclass(frozen=True)
class JointGeometry:
    """The slip-joint: MP (straight part below, bottom at z = 0) and TP above it.

    The TP is steeper than the MP (beta < alpha), so when lowered onto the MP its
    inner surface first touches the MP's outer cone at the TP's lower edge.
    """

    mp: ConePart
    tp: ConePart

    def __post_init__(self) -> None:
        if self.mp.straight_part != "below":
            raise ValueError(
                "the MP's straight part must be below its cone (straight_part='below')"
            )
        if self.tp.straight_part != "above":
            raise ValueError(
                "the TP's straight part must be above its cone (straight_part='above')"
            )
        if not self.tp.half_angle_deg < self.mp.half_angle_deg:
            raise ValueError(
                f"the TP half-angle beta = {self.tp.half_angle_deg} deg must be smaller than "
                f"the MP half-angle alpha = {self.mp.half_angle_deg} deg (first contact at the "
                "TP's lower edge)"
            )
        r_edge = self.tp.cone_bottom_outer_radius - self.tp.thickness
        r_lo, r_hi = self.mp.cone_top_outer_radius, self.mp.cone_bottom_outer_radius
        if not r_lo < r_edge <= r_hi:
            raise ValueError(
                f"the TP's inner radius at its lower edge ({r_edge:.6g} m) must lie between "
                f"the MP's outer cone radii ({r_lo:.6g} m at the top, {r_hi:.6g} m at the "
                "bottom) so that the TP lands on the MP cone"
            )

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> JointGeometry:
        """Build from ``{"mp": {...}, "tp": {...}}`` (the ``[geometry]`` TOML table)."""
        missing = {"mp", "tp"} - set(data)
        if missing:
            raise ValueError(f"[geometry] lacks the table(s) {sorted(missing)}")
        unknown = set(data) - {"mp", "tp"}
        if unknown:
            raise ValueError(f"[geometry] has unknown table(s) {sorted(unknown)}")
        return cls(
            mp=ConePart.from_dict({"straight_part": "below", **data["mp"]}, "geometry.mp"),
            tp=ConePart.from_dict({"straight_part": "above", **data["tp"]}, "geometry.tp"),
        )

    @property
    def first_contact_height(self) -> float:
        """Global z [m] of the TP's lower edge when its inner surface first touches the MP.

        Solves R_i,TP(lower edge) = R_o,MP(z) on the MP cone.
        """
        r_edge = self.tp.cone_bottom_outer_radius - self.tp.thickness
        s = (self.mp.cone_bottom_outer_radius - r_edge) / math.tan(self.mp.half_angle)
        return self.mp.cone_bottom_z + s

    @property
    def tp_offset(self) -> float:
        """Global z [m] of the TP's lower end (= first_contact_height at placement)."""
        return self.first_contact_height

    @property
    def overlap(self) -> float:
        """Axial overlap [m] at first contact: MP top minus TP lower edge."""
        return self.mp.total_length - self.first_contact_height

    @property
    def full_contact_overlap(self) -> float:
        """Overlap [m] at which the TP has slid to full contact: overlap sin(alpha)/sin(beta)."""
        return self.overlap * math.sin(self.mp.half_angle) / math.sin(self.tp.half_angle)

    @property
    def required_slip(self) -> float:
        """docs/physics.md §2.2 slip to full contact, L_slip = L_overlap (1 - sin beta / sin alpha) [m].

        L_overlap is the overlap *at full contact*, ``full_contact_overlap``, so that
        first-contact overlap + L_slip = L_overlap (which makes L_slip =
        overlap (sin alpha / sin beta - 1)).
        """
        ratio = math.sin(self.tp.half_angle) / math.sin(self.mp.half_angle)
        return self.full_contact_overlap * (1.0 - ratio)


@dataclass(frozen=True)
class MeshOptions:
    """Hexahedral mesh resolution of a part.

    ``n_circumferential`` elements around (a multiple of 4), elements of about
    ``axial_size`` m along the axis, ``n_layers`` through the wall, and gmsh
    geometry order ``geometry_order`` (2: hex27 with curved edges).

    Contact zone: with ``contact_axial_size`` > 0 [m], the cone walls of both parts
    between ``contact_zone_below`` m below and ``contact_zone_above`` m above the TP's
    lower edge (at placement) get elements of that axial size. The contact band grows
    from the TP edge by about settlement x tan(beta) / (tan(alpha) - tan(beta)) (20 x the
    settlement for the scaled joint), so it is only resolved by a fine axial mesh there.
    The contact surfaces (``tags.MP_CONTACT``, ``tags.TP_CONTACT``) are then the cone walls
    inside the zone: contact above it is not modelled (``solver.installation.observers.ContactZoneGuard``
    stops a run whose contact band reaches the zone's top).
    """

    n_circumferential: int = 48
    axial_size: float = 0.08
    n_layers: int = 1
    geometry_order: int = 2
    contact_axial_size: float = 0.0  #: axial element size in the contact zone [m]; 0: axial_size
    contact_zone_below: float = 0.03  #: contact zone below the TP's lower edge (on the MP) [m]
    contact_zone_above: float = 0.15  #: contact zone above the TP's lower edge [m]
    #: parallel distribution: "sectors" (equal angular sectors about the axis, each rank gets
    #: a sector of both parts, so the contact work is shared) or "graph" (DOLFINx's default
    #: graph partitioner, which tends to give a whole part to one rank)
    partition: str = "sectors"

    def __post_init__(self) -> None:
        n = self.n_circumferential
        if not (isinstance(n, int) and n >= 8 and n % 4 == 0):
            raise ValueError(
                f"n_circumferential must be an integer multiple of 4 and >= 8, got {n!r}"
            )
        if not self.axial_size > 0:
            raise ValueError(f"axial_size must be positive, got {self.axial_size} m")
        if not (isinstance(self.n_layers, int) and self.n_layers >= 1):
            raise ValueError(f"n_layers must be an integer >= 1, got {self.n_layers!r}")
        if self.geometry_order not in (1, 2):  # DOLFINx reads gmsh hexahedra up to hex27
            raise ValueError(f"geometry_order must be 1 or 2, got {self.geometry_order!r}")
        if not self.contact_axial_size >= 0:
            raise ValueError(f"contact_axial_size must be >= 0 m, got {self.contact_axial_size}")
        if self.partition not in ("sectors", "graph"):
            raise ValueError(f"partition must be 'sectors' or 'graph', got {self.partition!r}")
        if not (self.contact_zone_below >= 0 and self.contact_zone_above > 0):
            raise ValueError(
                "contact zone must have contact_zone_below >= 0 and contact_zone_above > 0 m, "
                f"got {self.contact_zone_below} and {self.contact_zone_above}"
            )

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> MeshOptions:
        """Build from a plain dict (the ``[mesh]`` TOML table)."""
        return construct(cls, data, "mesh")

    def n_axial(self, length: float, in_contact_zone: bool = False) -> int:
        """Number of elements along an axial segment of ``length`` m."""
        size = (
            self.contact_axial_size
            if in_contact_zone and self.contact_axial_size > 0
            else self.axial_size
        )
        return max(1, math.ceil(length / size - 1e-9))


def material_from_dict(data: dict[str, Any]) -> Material:
    """Build a :class:`Material` from the ``[material]`` table (E [Pa], nu, rho [kg/m^3])."""
    return construct(Material, data, "material")


def geometry_from_case(case: dict[str, Any]) -> tuple[JointGeometry, Material, MeshOptions]:
    """Joint, material and mesh options from a case dict (:func:`common.case.read_case`).

    Uses ``[geometry.mp]``, ``[geometry.tp]``, ``[material]`` and ``[mesh]``; other
    tables are ignored; a missing ``[material]`` or ``[mesh]`` gives the defaults.
    """
    try:
        return geometry_from_tables(case)
    except ValueError as e:
        raise ValueError(f"{case.get('_source', 'case')}: {e}") from None


def geometry_from_tables(case: dict[str, Any]) -> tuple[JointGeometry, Material, MeshOptions]:
    """:func:`geometry_from_case` whose ValueError does not name the case file (for callers that
    name it themselves)."""
    if "geometry" not in case:
        raise ValueError("no [geometry] table")
    return (
        JointGeometry.from_dict(case["geometry"]),
        material_from_dict(case.get("material", {})),
        MeshOptions.from_dict(case.get("mesh", {})),
    )


def load_geometry(
    path: str | Path, overrides: list[str] | None = None
) -> tuple[JointGeometry, Material, MeshOptions]:
    """:func:`geometry_from_case` of a TOML case file (or preset name, e.g. ``"full_scale"``)
    with optional ``section.key=value`` overrides."""
    return geometry_from_case(read_case(path, overrides))
