#!/usr/bin/env python3
"""Reads the VTU files written by `cargo run --example vtu_samples -- DIR` with meshio and
checks their content, proving an independent reader accepts every encoding we write."""
import sys
import xml.etree.ElementTree as ET

import meshio
import numpy as np

d, nodes, elements, particles = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4])
for enc in ("ascii", "base64", "appended"):
    m = meshio.read(f"{d}/mesh_{enc}.vtu")
    assert m.points.shape == (nodes, 3), m.points.shape
    assert m.cells[0].type == "tetra10", m.cells[0].type
    assert len(m.cells[0].data) == elements
    assert set(np.unique(m.cell_data["partition"][0])) == {0, 1, 2}
    assert (m.cell_data["material"][0] == 1).all()
    p = meshio.read(f"{d}/particles_{enc}.vtu")
    n = particles
    assert p.points.shape == (n, 3)
    expect = np.sin(np.arange(n * 3) * 0.37).reshape(n, 3)
    assert np.array_equal(p.points, expect), "points differ"
    assert np.array_equal(p.point_data["stress"], (np.arange(n * 6) - 0.5).reshape(n, 6))
    assert np.array_equal(p.point_data["id"].ravel(), np.arange(1, n + 1))
    print(f"meshio read {enc}: ok")
root = ET.parse(f"{d}/run.pvd").getroot()
files = [e.get("file") for e in root.iter("DataSet")]
assert files == ["particles_ascii.vtu", "particles_base64.vtu", "particles_appended.vtu"], files
print("pvd: ok")
