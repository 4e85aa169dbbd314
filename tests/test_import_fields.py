"""Field exports as terminals write them (fields.isoxml_fields, fields.kml): ISO 11783-10 external
files (XFR/XFC) in versions 3 and 4, an empty guidance pattern skipped and named, a hole written
as a boundary polygon of its own, an invalid KML polygon repaired and named; generated files with
a known truth (tests/import_recordings.py)."""
from __future__ import annotations

import json

import numpy as np
import pytest

from agrobot.fields.readers import read_fields, read_folder
from tests.import_recordings import write_xfr_taskdata


@pytest.mark.parametrize("version", [3, 4])
def test_an_export_in_external_files_is_read_with_its_hole_and_lines(tmp_path, version):
    folder = write_xfr_taskdata(tmp_path / "td", version)
    (field,) = read_fields(folder / "TASKDATA.XML")
    # truth: 200 x 100 m less a 20 x 10 m hole (the file's rectangles, on a sphere: within 1 %)
    assert field.holes == 1 and abs(field.boundary.area - (20000.0 - 200.0)) < 0.01 * 19800.0
    from shapely.geometry import Polygon

    assert abs(Polygon(field.boundary.interiors[0]).area - 200.0) < 0.01 * 200.0
    if version >= 4:
        assert [ln.name for ln in field.lines] == ["AB"] and abs(field.lines[0].length - 140.0) < 2.0
        assert "GPN1" in field.properties["skipped"] and "skipped" in field.properties["skipped"]
    fields, skipped = read_folder(folder)
    assert [f.name for f in fields] == ["north field"] and any("XFC" in s for s in skipped)


def test_a_missing_external_file_is_named(tmp_path):
    folder = write_xfr_taskdata(tmp_path / "td")
    (folder / "PFD00001.XML").unlink()
    with pytest.raises(Exception, match="XFR A='PFD00001': no PFD00001.XML"):
        read_fields(folder / "TASKDATA.XML")


def test_a_self_intersecting_kml_polygon_is_repaired_and_named_beside_a_good_one(tmp_path):
    ring = "5.0,52.0 5.01,52.01 5.01,52.0 5.0,52.01 5.0,52.0"          # a bow tie: two triangles
    square = "5.0,52.0 5.01,52.0 5.01,52.01 5.0,52.01 5.0,52.0"
    marks = "".join(f"<Placemark><name>{n}</name><Polygon><outerBoundaryIs><LinearRing><coordinates>{c}</coordinates>"
                    f"</LinearRing></outerBoundaryIs></Polygon></Placemark>" for n, c in (("bowtie", ring), ("square", square)))
    line = "<Placemark><name>AB</name><LineString><coordinates>5.001,52.001 5.009,52.009</coordinates></LineString></Placemark>"
    (tmp_path / "fields.kml").write_text(f'<kml xmlns="http://www.opengis.net/kml/2.2"><Document>{marks}{line}</Document></kml>')
    fields = {f.name: f for f in read_fields(tmp_path / "fields.kml")}
    assert set(fields) == {"bowtie_1", "bowtie_2", "square"}
    # each triangle of the bow tie is a quarter of the square (same corners)
    for k in (1, 2):
        assert abs(fields[f"bowtie_{k}"].boundary.area / fields["square"].boundary.area - 0.25) < 0.01
        assert "make_valid" in fields[f"bowtie_{k}"].properties["repaired"]
        assert fields[f"bowtie_{k}"].boundary.is_valid


@pytest.mark.parametrize("suffix", [".geojson", ".wkt"])
def test_a_self_intersecting_polygon_in_geojson_or_wkt_is_repaired_and_named(tmp_path, suffix):
    """The bow tie of the KML test in the other shape formats: two triangles of a quarter of the
    square on the same corners each (an area computed independently, by the shoelace formula)."""
    bow = [[5.0, 52.0], [5.01, 52.01], [5.01, 52.0], [5.0, 52.01], [5.0, 52.0]]
    square = [[5.0, 52.0], [5.01, 52.0], [5.01, 52.01], [5.0, 52.01], [5.0, 52.0]]
    if suffix == ".geojson":
        feats = [{"type": "Feature", "properties": {"name": n}, "geometry": {"type": "Polygon", "coordinates": [r]}}
                 for n, r in (("bowtie", bow), ("square", square))]
        (tmp_path / "f.geojson").write_text(json.dumps({"type": "FeatureCollection", "features": feats}))
        fields = {f.name: f for f in read_fields(tmp_path / "f.geojson")}
        names = ("bowtie_1", "bowtie_2")
    else:
        ring = ", ".join(f"{x} {y}" for x, y in bow)
        (tmp_path / "f.wkt").write_text(f"POLYGON (({ring}))\n")
        fields = {f.name: f for f in read_fields(tmp_path / "f.wkt", "EPSG:4326")}
        names = ("f_1", "f_2")
    assert set(names) <= set(fields)
    local = fields[names[0]].boundary
    xy = np.asarray(local.exterior.coords)
    shoelace = 0.5 * abs(np.dot(xy[:-1, 0], xy[1:, 1]) - np.dot(xy[1:, 0], xy[:-1, 1]))
    # the square's area on the ground: 0.01 deg of longitude x 0.01 deg of latitude near 52 N
    ground = (0.01 * np.pi / 180 * 6371000 * np.cos(np.radians(52.005))) * (0.01 * np.pi / 180 * 6371000)
    for name in names:
        assert fields[name].boundary.is_valid and "make_valid" in fields[name].properties["repaired"]
        assert abs(fields[name].boundary.area / ground - 0.25) < 0.01
    assert abs(shoelace - local.area) < 1e-6 * local.area
