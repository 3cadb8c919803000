"""Writes the STEP test files of the `step` crate with OpenCASCADE (pip install cadquery-ocp),
and `expected.json` with what OpenCASCADE itself reads back from each: the numbers of faces,
edges and vertices of the shape, and the length unit written.

Run from anywhere: python3 crates/step/tests/data/make_step.py
"""
import json
import math
import os
import re

from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace
from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox, BRepPrimAPI_MakeCylinder, BRepPrimAPI_MakeSphere
from OCP.GeomConvert import GeomConvert
from OCP.Geom import Geom_SphericalSurface, Geom_RectangularTrimmedSurface
from OCP.gp import gp_Ax2, gp_Ax3, gp_Dir, gp_Pnt
from OCP.IFSelect import IFSelect_RetDone
from OCP.Interface import Interface_Static
from OCP.STEPControl import STEPControl_AsIs, STEPControl_Reader, STEPControl_Writer
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE, TopAbs_VERTEX
from OCP.collections import IndexedMap_TopoDS_Shape_TopTools_ShapeMapHasher as TopTools_IndexedMapOfShape
from OCP.TopExp import TopExp

HERE = os.path.dirname(os.path.abspath(__file__))


def write(shape, name, schema, unit):
    Interface_Static.SetCVal_s("write.step.schema", schema)
    Interface_Static.SetCVal_s("write.step.unit", unit)
    w = STEPControl_Writer()
    Interface_Static.SetCVal_s("write.step.unit", unit)
    assert w.Transfer(shape, STEPControl_AsIs) == IFSelect_RetDone
    path = os.path.join(HERE, name)
    assert w.Write(path) == IFSelect_RetDone
    # The file's date and product numbering change from run to run; fix them.
    text = open(path).read()
    text = re.sub(r"'\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d'", "'2026-01-01T00:00:00'", text)
    text = re.sub(r"STEP translator 8\.0 \d+", "STEP translator 8.0", text)
    open(path, "w").write(text)
    return path


def count(shape, kind):
    m = TopTools_IndexedMapOfShape()
    TopExp.MapShapes_s(shape, kind, m)
    return m.Size()


def read_back(path):
    r = STEPControl_Reader()
    assert r.ReadFile(path) == IFSelect_RetDone
    r.TransferRoots()
    s = r.OneShape()
    return {
        "faces": count(s, TopAbs_FACE),
        "edges": count(s, TopAbs_EDGE),
        "vertices": count(s, TopAbs_VERTEX),
    }


def unit_of(path):
    text = open(path).read()
    m = re.search(r"LENGTH_UNIT\(\) NAMED_UNIT\(\*\) SI_UNIT\(([^,]*),\.METRE\.\)", text)
    return {"$": "m", ".MILLI.": "mm", ".CENTI.": "cm"}[m.group(1)]


expected = {}
cases = [
    ("box_ap214.stp", BRepPrimAPI_MakeBox(10.0, 20.0, 30.0).Shape(), "AP214IS", "MM"),
    (
        "cylinder_ap203.stp",
        BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(1, 2, 3), gp_Dir(0, 0, 1)), 5.0, 12.0).Shape(),
        "AP203",
        "M",
    ),
]
# A rational B-spline face: an eighth of a sphere converted to NURBS (weights != 1).
sph = Geom_SphericalSurface(gp_Ax3(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1)), 4.0)
patch = Geom_RectangularTrimmedSurface(sph, 0.0, math.pi / 2, 0.0, math.pi / 3)
nurbs = GeomConvert.SurfaceToBSplineSurface_s(patch)
cases.append(
    ("nurbs_ap242.stp", BRepBuilderAPI_MakeFace(nurbs, 1e-7).Face(), "AP242DIS", "M")
)
for name, shape, schema, unit in cases:
    path = write(shape, name, schema, unit)
    e = read_back(path)
    e["unit"] = unit_of(path)
    expected[name] = e
with open(os.path.join(HERE, "expected.json"), "w") as f:
    json.dump(expected, f, indent=1, sort_keys=True)
    f.write("\n")
print(json.dumps(expected, indent=1, sort_keys=True))
