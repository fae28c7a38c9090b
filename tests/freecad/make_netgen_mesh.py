# SPDX-License-Identifier: LGPL-2.1-or-later
"""Writes a Netgen tet mesh of a cylinder to argv[1] (.vol), with Debian's python3-netgen."""
import sys

from netgen.csg import CSGeometry, Cylinder, OrthoBrick, Pnt

geo = CSGeometry()
geo.Add(Cylinder(Pnt(0, 0, 0), Pnt(0, 0, 1), 5) * OrthoBrick(Pnt(-6, -6, 0), Pnt(6, 6, 12)))
mesh = geo.GenerateMesh(maxh=2.0)
mesh.Save(sys.argv[1])
