"""The geoms' triangles now live in the render core (:mod:`nbst.render.core.geoms`), shared by
every 3D video; this name stays for the importers outside render (nbst.export)."""
from __future__ import annotations

from nbst.render.core.geoms import (BOX, CAPSULE, CYLINDER, ELLIPSOID, HFIELD, HIDDEN_GROUPS, MESH, PLANE, SPHERE,
                                    arrow_solid, geom_rgba, geom_rows, region_outline, region_solid, sphere_rows,
                                    visible_geoms)

__all__ = ["PLANE", "HFIELD", "SPHERE", "CAPSULE", "ELLIPSOID", "CYLINDER", "BOX", "MESH", "HIDDEN_GROUPS",
           "geom_rgba", "geom_rows", "visible_geoms", "region_solid", "region_outline", "arrow_solid", "sphere_rows"]
