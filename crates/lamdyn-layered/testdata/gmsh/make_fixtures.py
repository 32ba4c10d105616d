#!/usr/bin/env python3
"""Writes the Gmsh fixtures of lamdyn-layered's surface-plan tests (run here; needs
`pip install gmsh==4.15.2`).

plate-unstructured.msh   the small test plate's plan, 0.5 x 0.4 m centred on the origin,
                         unstructured 4-node quads (Frontal-Delaunay for quads, recombined):
                         nodes of degree 3 and 5, elements of varying size and shape
small-laminate-quad9-mm.msh
                         the test bench's small laminate (lamdyn-testbench
                         tests/data/small_laminate.toml), 0.6 x 0.5 m centred on the origin,
                         in mm, unstructured 9-node quads (the pipeline's Gmsh-plan test)
"""
import gmsh


def rectangle(name, corner, size, element_size, order):
    """Unstructured quads of the given order over a rectangle: Frontal-Delaunay for quads,
    recombined, every element about element_size wide."""
    gmsh.model.add(name)
    occ = gmsh.model.occ
    s = occ.addRectangle(corner[0], corner[1], 0, size[0], size[1])
    occ.synchronize()
    gmsh.model.addPhysicalGroup(2, [s], name=name)
    gmsh.option.setNumber("Mesh.Algorithm", 8)
    gmsh.option.setNumber("Mesh.RecombineAll", 1)
    gmsh.option.setNumber("Mesh.RecombinationAlgorithm", 1)
    gmsh.option.setNumber("Mesh.MeshSizeMax", element_size)
    gmsh.option.setNumber("Mesh.MeshSizeMin", element_size)
    gmsh.option.setNumber("Mesh.ElementOrder", order)
    gmsh.option.setNumber("Mesh.SecondOrderIncomplete", 0)
    gmsh.model.mesh.generate(2)


gmsh.initialize()
gmsh.option.setNumber("General.Terminal", 0)
gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
rectangle("plate", (-0.25, -0.2), (0.5, 0.4), 0.11, 1)
gmsh.write("plate-unstructured.msh")
gmsh.model.remove()
rectangle("laminate", (-300.0, -250.0), (600.0, 500.0), 100.0, 2)
gmsh.write("small-laminate-quad9-mm.msh")
gmsh.finalize()
