"""Unit tests of cases/elbow/bend.py (the wear along the elbow, both codes), without
OpenFOAM: small field files and an scg CSV written here.

    python3 -m unittest discover -s cases/elbow -p 'test_bend.py'
"""
import contextlib
import io
import json
import math
import os
import shutil
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bend  # noqa: E402

R = bend.R


def extrados(theta_deg):
    """A wall point on the bend's outer side at angle theta (pipe radius 25 mm)."""
    t = math.radians(theta_deg)
    r = R + 0.025
    return (r * math.sin(t), R - r * math.cos(t), 0.0)


class Zones(unittest.TestCase):
    def test_zones_follow_the_pipe(self):
        self.assertEqual(bend.zone((-0.29, -0.025, 0.0), 30)[0], "inlet leg 250-300 mm")
        self.assertEqual(bend.zone((-0.3, 0.0, 0.0), 30)[0], "inlet leg 250-300 mm")
        self.assertEqual(bend.zone((-0.01, 0.025, 0.0), 30)[0], "inlet leg 0-50 mm")
        name, theta = bend.zone(extrados(45), 30)
        self.assertEqual(name, "bend outer 30-60°")
        self.assertAlmostEqual(theta, 45.0)
        t = math.radians(45)
        inner = ((R - 0.025) * math.sin(t), R - (R - 0.025) * math.cos(t), 0.0)
        self.assertEqual(bend.zone(inner, 10)[0], "bend inner 40-50°")
        self.assertEqual(bend.zone((0.1, 0.076, 0.0), 30)[0], "outlet leg 0-50 mm")
        self.assertEqual(bend.zone((0.1, 0.375, 0.0), 30)[0], "outlet leg 250-300 mm")
        self.assertEqual(bend.zone((0.1, 0.09, 0.0), 30, 0.025)[0], "outlet leg 0-25 mm")

    def test_both_codes_side_by_side(self):
        d = tempfile.mkdtemp()
        try:
            def field(kind, values):
                body = " ".join(values)
                return (f"boundaryField\n{{\n    walls\n    {{\n        type calculated;\n"
                        f"        value nonuniform List<{kind}> \n{len(values)}\n({body})\n;\n    }}\n}}\n")
            # three faces: the extrados at 45°, at 75°, and the outlet leg 120 mm up
            faces = [extrados(45), extrados(75), (0.1, R + 0.12, 0.0)]
            os.makedirs(os.path.join(d, "t"))
            with open(os.path.join(d, "t", "kinematicCloudQ"), "w") as f:
                f.write(field("scalar", ["6e-15", "3e-15", "1e-15"]))
            with open(os.path.join(d, "C"), "w") as f:
                f.write(field("vector", ["(%r %r %r)" % c for c in faces]))
            with open(os.path.join(d, "s.csv"), "w") as f:
                f.write("patch,face,x,y,z,area_m2,impacts,mass_kg,volume_m3,depth_rate_m_per_s\n")
                for k, (c, v) in enumerate(zip(faces, ["2e-15", "5e-15", "3e-15"])):
                    f.write(f"walls,{k},{c[0]!r},{c[1]!r},{c[2]!r},1e-4,1,1e-9,{v},1e-12\n")
                f.write("outlet,5,0.1,0.375,0.0,1e-4,1,1e-9,9e-15,1e-12\n")   # not a wall
            with contextlib.redirect_stdout(io.StringIO()) as o:
                bend.main(["bend.py", os.path.join(d, "t"), os.path.join(d, "C"),
                           os.path.join(d, "s.csv"), "--json", os.path.join(d, "b.json")])
            out = o.getvalue()
            with open(os.path.join(d, "b.json")) as f:
                t = json.load(f)
            z = {r["zone"]: (r["openfoam"], r["scg"]) for r in t["zones"]}
            self.assertAlmostEqual(z["bend outer 30-60°"][0], 0.6)
            self.assertAlmostEqual(z["bend outer 30-60°"][1], 0.2)
            self.assertAlmostEqual(z["bend outer 60-90°"][1], 0.5)
            self.assertAlmostEqual(z["outlet leg 100-150 mm"][0], 0.1)
            self.assertAlmostEqual(t["scg_total"], 1e-14)
            self.assertEqual(t["openfoam_top_zone"], "bend outer 30-60°")
            self.assertEqual(t["scg_top_zone"], "bend outer 60-90°")
            self.assertAlmostEqual(t["openfoam_deepest"]["angle"], 45.0)
            self.assertAlmostEqual(t["scg_deepest"]["angle"], 75.0)
            self.assertIn("(different)", out)
            with self.assertRaises(SystemExit):
                bend.main(["bend.py", os.path.join(d, "t"), os.path.join(d, "C"),
                           os.path.join(d, "s.csv"), "--bin", "7"])
        finally:
            shutil.rmtree(d)


if __name__ == "__main__":
    unittest.main()
