"""Physical group ids of the gmsh models (cell and facet tags in DOLFINx).

Joint model (MP and TP as two disjoint volumes in one mesh):

* cells: ``MP_VOLUME``, ``TP_VOLUME``
* facets: ``MP_CLAMPED`` (MP bottom annulus), ``TP_TOP`` (TP top annulus, loaded),
  ``MP_CONTACT`` (MP outer cone surface), ``TP_CONTACT`` (TP inner cone surface); with a
  contact zone (``MeshOptions.contact_axial_size`` > 0) only their parts inside the zone.

Single tube (``create_tube_mesh``): ``VOLUME``; ``BOTTOM`` and ``TOP`` annuli,
``OUTER`` and ``INNER`` lateral surfaces over the whole length (cone and straight
part). The tube ids coincide with the joint ids of the same role.
"""

MP_VOLUME = 1
TP_VOLUME = 2
MP_CLAMPED = 11
TP_TOP = 12
MP_CONTACT = 13
TP_CONTACT = 14

VOLUME = MP_VOLUME
BOTTOM = 11
TOP = 12
OUTER = 13
INNER = 14

#: physical group names as written into the gmsh model
JOINT_NAMES = {
    MP_VOLUME: "mp_volume",
    TP_VOLUME: "tp_volume",
    MP_CLAMPED: "mp_clamped",
    TP_TOP: "tp_top",
    MP_CONTACT: "mp_contact",
    TP_CONTACT: "tp_contact",
}
TUBE_NAMES = {VOLUME: "volume", BOTTOM: "bottom", TOP: "top", OUTER: "outer", INNER: "inner"}

#: the joint's ids by the names that case files use (``[contact] slave``, ``[modal] clamped``)
BY_NAME = {
    "MP_VOLUME": MP_VOLUME,
    "TP_VOLUME": TP_VOLUME,
    "MP_CLAMPED": MP_CLAMPED,
    "TP_TOP": TP_TOP,
    "MP_CONTACT": MP_CONTACT,
    "TP_CONTACT": TP_CONTACT,
}
