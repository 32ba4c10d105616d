#!/usr/bin/env python3
"""Writes the Gmsh fixtures of lamdyn-fem's mesh tests (run here; needs `pip install gmsh==4.15.2`).

plate-v22.msh / plate-v41.msh   0.3 x 0.2 m rectangle, 6 x 4 transfinite quads, physical groups
                                "plate" (surface), "long edges" (curves), "corner" (point)
dome-v41.msh                    a spherical patch (R = 1 m, away from the pole) meshed with quads
triangles-v41.msh               the rectangle left as triangles (must be refused)
binary-v41.msh                  the rectangle in binary MSH 4.1 (must be refused)
"""
import gmsh


def rectangle(recombine=True):
    gmsh.model.add("plate")
    occ = gmsh.model.occ
    s = occ.addRectangle(0, 0, 0, 0.3, 0.2)
    occ.synchronize()
    curves = [c[1] for c in gmsh.model.getBoundary([(2, s)], oriented=False)]
    for c in curves:
        x0, y0, _, x1, y1, _ = gmsh.model.getBoundingBox(1, c)
        n = 7 if abs(y1 - y0) < 1e-6 else 5
        gmsh.model.mesh.setTransfiniteCurve(c, n)
    gmsh.model.mesh.setTransfiniteSurface(s)
    if recombine:
        gmsh.model.mesh.setRecombine(2, s)
    long_edges = [c for c in curves if abs(gmsh.model.getBoundingBox(1, c)[4] - gmsh.model.getBoundingBox(1, c)[1]) < 1e-6]
    gmsh.model.addPhysicalGroup(2, [s], name="plate")
    gmsh.model.addPhysicalGroup(1, long_edges, name="long edges")
    pts = gmsh.model.getBoundary([(2, s)], recursive=True)
    gmsh.model.addPhysicalGroup(0, [pts[0][1]], name="corner")
    gmsh.model.mesh.generate(2)


def dome():
    gmsh.model.add("dome")
    occ = gmsh.model.occ
    occ.addSphere(0, 0, 0, 1.0, angle1=0.9, angle2=1.3, angle3=0.6)
    occ.synchronize()
    spherical = [e for e in gmsh.model.getEntities(2) if gmsh.model.getType(*e) == "Sphere"]
    gmsh.model.addPhysicalGroup(2, [spherical[0][1]], name="cap")
    gmsh.option.setNumber("Mesh.RecombineAll", 1)
    gmsh.option.setNumber("Mesh.Algorithm", 8)
    gmsh.option.setNumber("Mesh.SubdivisionAlgorithm", 1)
    gmsh.option.setNumber("Mesh.MeshSizeMax", 0.08)
    gmsh.model.mesh.generate(2)


gmsh.initialize()
gmsh.option.setNumber("General.Terminal", 0)
for version, name in [(2.2, "plate-v22.msh"), (4.1, "plate-v41.msh")]:
    gmsh.clear()
    rectangle()
    gmsh.option.setNumber("Mesh.MshFileVersion", version)
    gmsh.option.setNumber("Mesh.Binary", 0)
    gmsh.write(name)
gmsh.clear()
dome()
gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
gmsh.write("dome-v41.msh")
gmsh.option.setNumber("Mesh.RecombineAll", 0)
gmsh.option.setNumber("Mesh.SubdivisionAlgorithm", 0)
gmsh.clear()
rectangle(recombine=False)
gmsh.write("triangles-v41.msh")
gmsh.clear()
rectangle()
gmsh.option.setNumber("Mesh.Binary", 1)
gmsh.write("binary-v41.msh")
gmsh.finalize()
