"""Tests of cases/squarebend/vs_openfoam.py and of the patch-interaction mapping of
cases/cyclone/vs_openfoam.py on the squareBend scene; no OpenFOAM needed (standard library
only, < 1 s):

    python3 -m unittest discover -s cases/squarebend -p 'test_vs_openfoam.py'

The scene is cases/squarebend.toml; the mesh is the committed cases/squarebend/coarse.
"""
import contextlib
import io
import json
import os
import re
import shutil
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import vs_openfoam as sb  # noqa: E402
cyc = sb.cyc

SCENE = os.path.join(HERE, "..", "squarebend.toml")


def entry(text, key):
    m = re.search(r"^\s*" + re.escape(key) + r"\s+([^;]+);", text, re.M)
    return m.group(1).strip() if m else None


def block(text, name):
    """The body of `name { ... }` (nested braces counted)."""
    i = re.search(r"^\s*" + re.escape(name) + r"\s*\n?\s*\{", text, re.M).end()
    depth = 1
    for j in range(i, len(text)):
        depth += {"{": 1, "}": -1}.get(text[j], 0)
        if depth == 0:
            return text[i:j]
    raise AssertionError(f"unclosed {name}")


class Mapping(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp()
        self.base = cyc.read_text(SCENE).replace(
            'case = "squarebend/coarse"', f'case = "{os.path.join(HERE, "coarse")}"')

    def tearDown(self):
        shutil.rmtree(self.tmp)

    def cloud(self, text):
        p = os.path.join(self.tmp, "s.toml")
        with open(p, "w") as f:
            f.write(text)
        plan = cyc.make_cases(cyc.read_scene(p), os.path.join(self.tmp, "of"))
        return plan, cyc.read_text(os.path.join(plan["runs"][0]["dir"], "constant", "kinematicCloudProperties"))

    def test_scene_maps_to_local_interaction_stick_and_escape(self):
        plan, cloud = self.cloud(self.base)
        self.assertEqual(plan["patch_model"], "localInteraction")
        self.assertEqual(entry(cloud, "patchInteractionModel"), "localInteraction")
        pats = block(cloud, "localInteractionCoeffs")
        self.assertRegex(pats, r"walls \{ type stick; \}")
        self.assertRegex(pats, r"outlet \{ type escape; \}")
        self.assertRegex(pats, r"inlet \{ type escape; \}")
        self.assertNotIn("standardWallInteraction", cloud)
        self.assertEqual(entry(block(cloud, cyc.PPP), "patches"), "(inlet outlet walls)")
        self.assertEqual(plan["fate_patches"], ["inlet", "outlet", "walls"])
        self.assertEqual(entry(block(cloud, "constantProperties"), "rho0"), "2500.0")
        self.assertEqual(entry(block(cloud, "interpolationSchemes"), "U"), "cellPoint")
        inj = block(cloud, "injectionModels")
        for name, dia in (("d5", "5e-06"), ("d20", "2e-05"), ("d50", "5e-05"), ("d100", "0.0001")):
            b = block(inj, name)
            self.assertEqual(entry(b, "patch"), "inlet")
            self.assertEqual(entry(b, "parcelsPerSecond"), "100000.0")
            self.assertEqual(entry(b, "U0"), "(10.0 0.0 0.0)")
            # 100 steps of 5 parcels: the window as 99.5 steps (OpenFOAM would inject in a 101st)
            self.assertAlmostEqual(float(entry(b, "duration")), 99.5 * 5e-5, places=15)
            self.assertEqual(entry(block(b, "fixedValueDistribution"), "value"), dia)
        g = cyc.read_text(os.path.join(plan["runs"][0]["dir"], "constant", "g"))
        self.assertEqual(entry(g, "value"), "(0.0 0.0 0.0)")  # no gravity: the tutorial has none
        ctl = cyc.read_text(os.path.join(plan["runs"][0]["dir"], "system", "controlDict"))
        self.assertEqual(entry(ctl, "deltaT"), "5e-05")
        self.assertEqual(entry(ctl, "writeInterval"), "4000")
        self.assertEqual(plan["time"], "2000")
        self.assertEqual(plan["field"], "U")

    def test_rebound_with_friction_and_per_patch_overrides(self):
        text = self.base.replace('wall_model = "stick"',
                                 'wall_model = "rebound"\nrestitution = 0.9\nfriction = 0.2')
        # scg's Coulomb impact under OpenFOAM's mu: refused, naming the key
        with self.assertRaises(cyc.SceneError) as e:
            self.cloud(text)
        self.assertIn("flow.patches.friction_model", str(e.exception))
        self.assertIn("openfoam_fraction", str(e.exception))
        text = text.replace("friction = 0.2", 'friction = 0.2\nfriction_model = "openfoam_fraction"')
        plan, cloud = self.cloud(text)
        self.assertEqual(plan["patch_model"], "localInteraction")  # friction: not standardWallInteraction
        self.assertRegex(block(cloud, "localInteractionCoeffs"), r"walls \{ type rebound; e 0.9; mu 0.2; \}")
        self.assertEqual(plan["fate_patches"], ["inlet", "outlet"])  # bounces are no fate
        # per-patch overrides, as OpenFOAM's localInteraction (the table right after [flow.patches])
        text = self.base.replace('wall_model = "stick"', 'wall_model = "stick"\n\n[flow.patches.interaction]\n'
                                 'walls = { model = "rebound", restitution = 0.5 }\ninlet = { model = "stick" }')
        plan, cloud = self.cloud(text)
        pats = block(cloud, "localInteractionCoeffs")
        self.assertRegex(pats, r"walls \{ type rebound; e 0.5; mu 0.0; \}")
        self.assertRegex(pats, r"inlet \{ type stick; \}")
        self.assertRegex(pats, r"outlet \{ type escape; \}")

    def test_plain_rebound_stays_standard_wall_interaction(self):
        """The cyclone scenes' form (wall_model rebound, [material] restitution, no friction)."""
        text = self.base.replace('wall_model = "stick"', 'wall_model = "rebound"') + (
            "\n[material]\nyoungs_modulus = 1.0e8\npoisson_ratio = 0.3\nrestitution = 0.5\n")
        plan, cloud = self.cloud(text)
        self.assertEqual(plan["patch_model"], "standardWallInteraction")
        w = block(cloud, "standardWallInteractionCoeffs")
        self.assertEqual((entry(w, "type"), entry(w, "e"), entry(w, "mu")), ("rebound", "0.5", "0"))
        self.assertEqual(entry(block(cloud, cyc.PPP), "patches"), "(inlet outlet)")

    def test_bad_interactions_name_the_key(self):
        cases = [
            (self.base.replace('wall_model = "stick"', 'wall_model = "contact"'), "flow.patches.wall_model"),
            (self.base.replace('wall_model = "stick"', 'wall_model = "stick"\n\n[flow.patches.interaction]\n'
                               'walls = { model = "bounce" }'), "flow.patches.interaction.walls.model"),
            (self.base.replace('wall_model = "stick"', 'wall_model = "stick"\n\n[flow.patches.interaction]\n'
                               'roof = { model = "stick" }'), "flow.patches.interaction.roof"),
        ]
        for text, key in cases:
            with self.subTest(key=key):
                with self.assertRaises(cyc.SceneError) as e:
                    self.cloud(text)
                self.assertIn(f": {key}:", str(e.exception))


LOG = """Time = 0.2

Solving 3-D cloud kinematicCloud
    Current number of parcels       = 5
    Injector d5:
      - parcels added               = 4
      - mass introduced             = 1e-12
    Injector d50:
      - parcels added               = 3
    Parcel fate: system (number, mass)
      - escape                      = 2, 1e-12
    Parcel fate: patch inlet (number, mass)
      - escape                      = 0, 0
      - stick                       = 0, 0
    Parcel fate: patch outlet (number, mass)
      - escape                      = 2, 1e-12
      - stick                       = 0, 0
    Parcel fate: patch walls (number, mass)
      - escape                      = 0, 0
      - stick                       = 3, 1e-9

ExecutionTime = 0.5 s  ClockTime = 1 s
"""
POST_HEAD = ("# Time currentProc (coordinates0 coordinates1 coordinates2 coordinates3) (position0 position1 "
             "position2) celli tetFacei tetPti facei stepFraction origProc origId active typeId nParticle d "
             "dTarget (U0 U1 U2) rho age tTurb (UTurb0 UTurb1 UTurb2)\n")


def post_row(d, age):
    return (f"0.05 0 (0 0.1 0.2 0.7) (-0.5 -0.05 0) 10 11 1 11 0.5 0 1 1 -1 1 {d!r} 0 (10 0 0) 2500 "
            f"{age!r} 0 (0 0 0)\n")


class Results(unittest.TestCase):
    def test_grade_counts_stuck_airborne_and_escaped_per_class(self):
        """A finished run: 2 d5 out of the outlet, 2 d5 airborne, 3 d50 stuck on the walls
        (written inactive; the `active` list uniform-compact where all equal)."""
        d = tempfile.mkdtemp()
        try:
            run = os.path.join(d, "rho2500")
            lag = os.path.join(run, "0.2", "lagrangian", cyc.CLOUD)
            os.makedirs(lag)
            with open(os.path.join(run, "log.foam"), "w") as f:
                f.write(LOG)
            hdr = "FoamFile\n{\n    version 2.0;\n}\n\n"
            with open(os.path.join(lag, "d"), "w") as f:
                f.write(hdr + "5\n(\n5e-06\n5e-06\n5e-05\n5e-05\n5e-05\n)\n")
            with open(os.path.join(lag, "active"), "w") as f:
                f.write(hdr + "5(1 1 0 0 0)\n")
            for patch, rows in (("outlet", [(5e-6, 0.06), (5e-6, 0.07)]), ("walls", [(5e-5, 0.01)] * 3)):
                p = os.path.join(run, "postProcessing", "lagrangian", cyc.CLOUD, cyc.PPP, "0.2")
                os.makedirs(p, exist_ok=True)
                with open(os.path.join(p, patch + ".post"), "w") as f:
                    f.write(POST_HEAD + "".join(post_row(x, a) for x, a in rows))
            cls = lambda g, dia: {"group": g, "diameter": dia, "density": 2500.0}
            plan = {"classes": [cls("d5", 5e-6), cls("d50", 5e-5)],
                    "runs": [{"dir": run, "density": 2500.0, "groups": ["d5", "d50"]}],
                    "outlets": ["outlet"], "inlets": ["inlet"], "walls": ["walls"], "field": "U", "time": "2000",
                    "foam_interpolation": "cellPoint", "drag": "schiller_naumann", "dt": 5e-5,
                    "restitution": 1.0, "patch_model": "localInteraction",
                    "patch_interactions": {"inlet": {"model": "escape"}, "outlet": {"model": "escape"},
                                           "walls": {"model": "stick"}}}
            cyc.write_json(os.path.join(d, "plan.json"), plan)
            g = cyc.grade(d, os.path.join(d, "grade.json"))
            by = {c["group"]: c for c in g["classes"]}
            self.assertEqual([by["d5"][k] for k in ("fed", "escaped", "lost", "stuck", "held")], [4, 2, 0, 0, 2])
            self.assertEqual([by["d50"][k] for k in ("fed", "escaped", "lost", "stuck", "held")], [3, 0, 0, 3, 0])
            self.assertEqual(by["d50"]["patches"], {"walls": 3})
            self.assertEqual(g["log_fates"]["walls"], {"escape": 0, "stick": 3})
            self.assertFalse([n for n in g["notes"] if "against" in n or "neither" in n], g["notes"])
            fo = {c["group"]: c for c in sb.openfoam_fates(g, ["inlet"])}
            self.assertEqual([fo["d5"][f] for f in sb.FATES], [2, 0, 0, 2])
            self.assertEqual([fo["d50"][f] for f in sb.FATES], [0, 0, 3, 0])
        finally:
            shutil.rmtree(d)

    def test_uniform_and_listed_fields(self):
        d = tempfile.mkdtemp()
        try:
            p = os.path.join(d, "f")
            for text, want in (("FoamFile\n{\n}\n3{1}\n", [1, 1, 1]), ("FoamFile\n{\n}\n\n2\n(\n0\n1\n)\n", [0, 1]),
                               ("FoamFile\n{\n}\n0()\n", [])):
                with open(p, "w") as f:
                    f.write(text)
                self.assertEqual(cyc.foam_field(p, int), want)
        finally:
            shutil.rmtree(d)

    def test_wilson(self):
        lo, hi = sb.wilson(5, 10)
        self.assertAlmostEqual(lo, 0.2366, places=4)
        self.assertAlmostEqual(hi, 0.7634, places=4)
        lo, hi = sb.wilson(0, 500)
        self.assertEqual(lo, 0.0)
        self.assertAlmostEqual(hi, 0.00762, places=5)
        self.assertEqual(sb.wilson(0, 0), (None, None))
        self.assertTrue(sb.overlap((0.1, 0.3), (0.3, 0.5)))
        self.assertFalse(sb.overlap((0.1, 0.2), (0.3, 0.5)))
        self.assertIsNone(sb.overlap((None, None), (0.3, 0.5)))


class ScgSummary(unittest.TestCase):
    W, O, I = ["walls"], ["outlet"], ["inlet"]

    def fates(self, group):
        g = dict({"group": "d5", "diameter": 5e-6, "fed": 10}, **group)
        return sb.scg_fates({"groups": [g]}, self.W, self.O, self.I)[0]

    def test_per_patch_tables_in_their_shapes(self):
        for shape in (
            {"patches": {"walls": 3, "outlet": 5, "inlet": 1}},
            {"patches": {"walls": {"stuck": 3}, "outlet": {"escaped": 5}, "inlet": {"escaped": 1}}},
            {"patch_fates": {"walls": {"stuck": [0.1, 0.2, 0.3]}, "outlet": {"escaped": [0.1] * 5},
                             "inlet": {"escaped": [0.2]}}},
            {"fates": {"stuck": {"walls": 3}, "escaped": {"outlet": 5, "inlet": 1}}},
            {"patches": [{"patch": "walls", "fate": "stick", "count": 3}, {"patch": "outlet", "count": 5},
                         {"patch": "inlet", "count": 1}]},
            {"patches": {"walls": {"count": 3, "times": [1, 2, 3]}, "outlet": {"count": 5}, "inlet": {"count": 1}}},
        ):
            with self.subTest(shape=shape):
                f = self.fates(dict(shape, drained=5, lost=1, held=4))
                self.assertEqual([f[k] for k in sb.FATES], [5, 1, 3, 1], f)

    def test_scg_fates_table(self):
        """scg's `fates` per group: patches as rows with role, escaped and stuck (and masses)."""
        row = lambda p, role, e, st: {"patch": p, "role": role, "escaped": e, "escaped_mass": e * 2e-12,
                                      "stuck": st, "stuck_mass": st * 2e-12}
        f = self.fates({"drained": 5, "lost": 1, "held": 4, "fates": {
            "represented_mass": 2e-12, "initial": 0, "fed": 10, "fed_mass": 2e-11,
            "patches": [row("inlet", "inlet", 1, 0), row("outlet", "outlet", 5, 0), row("walls", "wall", 0, 3)],
            "drained": 0, "lost": 0, "lost_mass": 0.0, "airborne": 1, "airborne_mass": 2e-12, "conserved": True}})
        self.assertEqual([f[k] for k in sb.FATES], [5, 1, 3, 1], f)
        self.assertIn("per patch from 'patches'", f["how"])
        self.assertIn("airborne = airborne", f["how"])

    def test_fallbacks_and_missing_walls(self):
        f = self.fates({"drained": 5, "lost": 1, "held": 4, "stuck": 3})
        self.assertEqual([f[k] for k in sb.FATES], [5, 1, 3, 1])
        self.assertIn("walls = stuck", f["how"])
        f = self.fates({"drained": 5, "lost": 1, "held": 4, "drained_times": [], "lost_times": []})
        self.assertEqual((f["outlet"], f["inlet"], f["walls"], f["airborne"]), (5, 1, None, None))

    def test_table_prints_the_keys_when_walls_are_missing(self):
        d = tempfile.mkdtemp()
        try:
            grade = {"classes": [{"group": "d5", "diameter": 5e-6, "fed": 10, "escaped": 6, "lost": 0,
                                  "stuck": 0, "held": 4, "patches": {"outlet": 6}}]}
            cyc.write_json(os.path.join(d, "g.json"), grade)
            scg = {"groups": [{"group": "d5", "diameter": 5e-6, "fed": 10, "drained": 7, "lost": 0, "held": 3,
                               "drained_times": [], "lost_times": []}], "steps": 4000}
            cyc.write_json(os.path.join(d, "s.json"), scg)
            out = io.StringIO()
            with contextlib.redirect_stdout(out):
                rows, ok = sb.table(os.path.join(d, "g.json"), os.path.join(d, "s.json"), self.W, self.O, self.I,
                                    os.path.join(d, "f.json"))
            text = out.getvalue()
            self.assertIsNone(ok)
            self.assertIn("its group keys: diameter, drained, drained_times, fed, group, held, lost, lost_times", text)
            self.assertIn("all intervals overlap: unknown", text)
            outlet = next(r for r in rows if r["fate"] == "outlet")
            self.assertTrue(outlet["overlap"])  # 6/10 and 7/10
            # with per-patch counts: the verdict is given
            scg["groups"][0]["patches"] = {"outlet": 7, "walls": 0, "inlet": 0}
            cyc.write_json(os.path.join(d, "s.json"), scg)
            with contextlib.redirect_stdout(io.StringIO()) as o2:
                rows, ok = sb.table(os.path.join(d, "g.json"), os.path.join(d, "s.json"), self.W, self.O, self.I)
            self.assertTrue(ok, o2.getvalue())
            self.assertIn("all intervals overlap: yes", o2.getvalue())
            with open(os.path.join(d, "f.json")) as f:
                self.assertIn("rows", json.load(f))
        finally:
            shutil.rmtree(d)


class Erosion(unittest.TestCase):
    def test_the_scene_adds_particle_erosion_and_dnv_is_refused(self):
        tmp = tempfile.mkdtemp()
        try:
            base = cyc.read_text(SCENE).replace(
                'case = "squarebend/coarse"', f'case = "{os.path.join(HERE, "coarse")}"').replace(
                'wall_model = "stick"', 'wall_model = "rebound"')
            p = os.path.join(tmp, "s.toml")
            with open(p, "w") as f:
                f.write(base + '\n[erosion]\nmodel = "finnie"\nflow_stress = 2.0e9\n')
            plan = cyc.make_cases(cyc.read_scene(p), os.path.join(tmp, "of"))
            cloud = cyc.read_text(os.path.join(plan["runs"][0]["dir"], "constant", "kinematicCloudProperties"))
            e = block(cloud, "particleErosion1")
            self.assertEqual(entry(e, "type"), "particleErosion")
            self.assertEqual(entry(e, "patches"), "(walls)")
            self.assertEqual(float(entry(e, "p")), 2.0e9)
            self.assertEqual((float(entry(e, "psi")), float(entry(e, "K"))), (2.0, 2.0))
            # --erosion's scene: rebound, Finnie, and OpenFOAM's drag for scg too
            d = sb.erosion_scene(SCENE, os.path.join(tmp, "e.toml"), 1.5e9, 0.7)
            s = cyc.read_toml(d)
            self.assertEqual(s["drag"]["law"], "putnam")
            self.assertEqual(s["erosion"], {"model": "finnie", "flow_stress": 1.5e9})
            self.assertEqual(s["flow"]["patches"]["restitution"], 0.7)
            self.assertTrue(os.path.isabs(s["flow"]["case"]))
            with open(p, "w") as f:
                f.write(base + '\n[erosion]\nmodel = "dnv"\nwall_density = 7800.0\n')
            with self.assertRaises(cyc.SceneError) as c:
                cyc.read_scene(p)
            self.assertIn("erosion.model", str(c.exception))
        finally:
            shutil.rmtree(tmp)

    def test_side_by_side_sums_regions_and_finds_the_deepest(self):
        d = tempfile.mkdtemp()
        try:
            # two wall faces: OpenFOAM wears the first 3e-15 and the second 1e-15; scg the
            # other way round, in regions of 10 mm (faces 30 mm apart)
            def field(kind, values):
                body = " ".join(values)
                return (f"boundaryField\n{{\n    walls\n    {{\n        type calculated;\n"
                        f"        value nonuniform List<{kind}> \n2\n({body})\n;\n    }}\n}}\n")
            os.makedirs(os.path.join(d, "t"))
            with open(os.path.join(d, "t", "kinematicCloudQ"), "w") as f:
                f.write(field("scalar", ["3e-15", "1e-15"]))
            with open(os.path.join(d, "C"), "w") as f:
                f.write(field("vector", ["(0.005 0.005 0.005)", "(0.035 0.005 0.005)"]))
            with open(os.path.join(d, "s.csv"), "w") as f:
                f.write("patch,face,x,y,z,area_m2,impacts,mass_kg,volume_m3,depth_rate_m_per_s\n"
                        "walls,7,0.005,0.005,0.005,1e-4,1,1e-9,1e-15,1e-12\n"
                        "walls,9,0.035,0.005,0.005,1e-4,3,3e-9,3e-15,3e-12\n")
            with contextlib.redirect_stdout(io.StringIO()) as o:
                sb.erosion(os.path.join(d, "t"), os.path.join(d, "C"), ["walls"],
                           os.path.join(d, "s.csv"), 0.01, os.path.join(d, "e.json"))
            out = o.getvalue()
            self.assertIn("ratio 1.000", out)
            self.assertIn("region != scg's", out)
            self.assertIn("30.0 mm apart", out)
            with open(os.path.join(d, "e.json")) as f:
                j = json.load(f)
            self.assertFalse(j["same_region"])
            self.assertAlmostEqual(j["openfoam_total"], 4e-15)
            shares = sorted((round(r[1], 12), round(r[2], 12)) for r in j["regions"])
            self.assertEqual(shares, [(0.25, 0.75), (0.75, 0.25)])
        finally:
            shutil.rmtree(d)


if __name__ == "__main__":
    unittest.main()
