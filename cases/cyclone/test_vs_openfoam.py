"""Tests of cases/cyclone/vs_openfoam.py that need no OpenFOAM (standard library only):

    python3 -m unittest discover -s cases/cyclone -p 'test_vs_openfoam.py'

The scene is the test fixture cases/cyclone/fixture-patch-feeders.toml (cases/cyclone.toml
with inlet-patch feeders); the mesh is the committed cases/cyclone/coarse.
"""
import json
import os
import re
import shutil
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import vs_openfoam as vs  # noqa: E402

FIXTURE = os.path.join(HERE, "fixture-patch-feeders.toml")


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


class Scene(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp()

    def tearDown(self):
        shutil.rmtree(self.tmp)

    def write(self, text, name="s.toml"):
        p = os.path.join(self.tmp, name)
        with open(p, "w") as f:
            f.write(text)
        return p

    def test_fixture_maps_to_one_case_with_an_injector_per_class(self):
        sc = vs.read_scene(FIXTURE)
        self.assertEqual([c["group"] for c in sc["classes"]], ["d2", "d5", "d10", "d20"])
        self.assertEqual(sc["field"], "UMean")
        self.assertEqual(sc["time"], "800")
        plan = vs.make_cases(sc, self.tmp)
        self.assertEqual(len(plan["runs"]), 1)
        d = plan["runs"][0]["dir"]
        cloud = vs.read_text(os.path.join(d, "constant", "kinematicCloudProperties"))
        self.assertEqual(entry(block(cloud, "constantProperties"), "rho0"), "2000.0")
        inj = block(cloud, "injectionModels")
        for name, dia in (("d2", "2e-06"), ("d5", "5e-06"), ("d10", "1e-05"), ("d20", "2e-05")):
            b = block(inj, name)
            self.assertEqual(entry(b, "type"), "patchInjection")
            self.assertEqual(entry(b, "patch"), "inlet")
            self.assertEqual(entry(b, "parcelsPerSecond"), "400.0")
            self.assertEqual(entry(b, "duration"), "1.0")
            self.assertEqual(entry(b, "SOI"), "0.0")
            self.assertEqual(entry(b, "nParticle"), "1")
            self.assertEqual(entry(b, "U0"), "(-10.0 0.0 0.0)")
            self.assertEqual(entry(block(b, "fixedValueDistribution"), "value"), dia)
        wall = block(cloud, "standardWallInteractionCoeffs")
        self.assertEqual(entry(wall, "type"), "rebound")
        self.assertEqual(entry(wall, "e"), "0.5")
        self.assertEqual(entry(wall, "mu"), "0")
        self.assertIn("sphereDrag", block(cloud, "particleForces"))
        self.assertIn("gravity", block(cloud, "particleForces"))
        self.assertEqual(entry(block(cloud, "interpolationSchemes"), "U"), "cellPoint")
        self.assertEqual(entry(block(cloud, vs.PPP), "patches"), "(inlet outlet)")
        ctl = vs.read_text(os.path.join(d, "system", "controlDict"))
        self.assertEqual(entry(ctl, "application"), "uncoupledKinematicParcelFoam")
        self.assertEqual(entry(ctl, "deltaT"), "0.0002")
        self.assertEqual(float(entry(ctl, "endTime")), 3.0)
        self.assertEqual(entry(ctl, "writeInterval"), "15000")
        g = vs.read_text(os.path.join(d, "constant", "g"))
        self.assertEqual(entry(g, "value"), "(0.0 0.0 -9.81)")
        th = vs.read_text(os.path.join(d, "constant", "thermophysicalProperties"))
        self.assertIn("mu 1.8e-05;", th)
        # p/(R T) is the scene's air density
        t = float(entry(vs.read_text(os.path.join(d, "0", "T")), "internalField").split()[1])
        self.assertAlmostEqual(vs.P_REF / (vs.R_UNIVERSAL / vs.MOL_WEIGHT * t), 1.2, places=12)
        self.assertTrue(os.path.isfile(os.path.join(d, "0", "U.gz")))
        self.assertTrue(os.path.isfile(os.path.join(d, "constant", "polyMesh", "owner.gz")))

    def test_overrides_and_densities(self):
        text = vs.read_text(FIXTURE).replace('case = "coarse"', f'case = "{os.path.join(HERE, "coarse")}"')
        # d20 heavier: a second OpenFOAM case (one cloud has one rho0)
        text = text.replace('name = "d20"\ndiameter = 2e-05\ndensity = 2000.0', 'name = "d20"\ndiameter = 2e-05\ndensity = 3000.0')
        p = self.write(text)
        sc = vs.read_scene(p, duration=0.4, feed_scale=0.25)
        self.assertEqual(sc["duration"], 0.4)
        self.assertEqual(sc["classes"][0]["rate"], 100.0)
        self.assertEqual(sc["classes"][0]["stop"], 0.4)  # the feed ends with the run
        plan = vs.make_cases(sc, os.path.join(self.tmp, "out"))
        self.assertEqual([r["groups"] for r in plan["runs"]], [["d2", "d5", "d10"], ["d20"]])
        self.assertEqual([r["density"] for r in plan["runs"]], [2000.0, 3000.0])
        with open(os.path.join(self.tmp, "out", "plan.json")) as f:
            self.assertEqual(len(json.load(f)["runs"]), 2)

    def test_bad_scenes_name_the_key(self):
        base = vs.read_text(FIXTURE).replace('case = "coarse"', f'case = "{os.path.join(HERE, "coarse")}"')
        cases = [
            (base.replace('patch = "inlet"\nrate = 400.0\nvelocity = [-10.0, 0.0, 0.0]\nstop = 1.0\n\n[[feeders]]\ngroup = "d5"',
                          'region = { kind = "box", min = [0.5, 0.3, 0.7], max = [0.52, 0.4, 0.9] }\nrate = 400.0\n'
                          'velocity = [-10.0, 0.0, 0.0]\nstop = 1.0\n\n[[feeders]]\ngroup = "d5"', 1), "feeders.0.patch"),
            (base.replace('dt = 2.0e-4', 'dt = "auto"'), "dt"),
            (base.replace('wall_model = "rebound"', 'wall_model = "contact"'), "flow.patches.wall_model"),
            (base.replace('walls = ["walls"]', 'walls = []'), "flow.patches.walls"),
            (base.replace('outlets = ["outlet"]', 'outlets = ["top"]'), "flow.patches.outlets"),
            (base.replace('group = "d20"\n', 'group = "d10"\n'), "groups.2"),
            (base.replace('patch = "inlet"\n', 'patch = "inlet"\nweight = "flux"\n', 1), "feeders.0.weight"),
        ]
        for text, key in cases:
            with self.subTest(key=key):
                p = self.write(text)
                with self.assertRaises(vs.SceneError) as e:
                    vs.make_cases(vs.read_scene(p), os.path.join(self.tmp, "o"))
                self.assertIn(f": {key}:", str(e.exception))

    def test_dispersion_freezes_the_scenes_turbulence_fields(self):
        base = vs.read_text(FIXTURE).replace('case = "coarse"', f'case = "{os.path.join(HERE, "coarse")}"')
        p = self.write(base + '\n[dispersion]\nmodel = "stochastic_ras"\nk = "kMean"\nomega = "omegaMean"\n')
        sc = vs.read_scene(p)
        self.assertEqual(sc["dispersion"]["ras_model"], "kOmegaSST")
        plan = vs.make_cases(sc, os.path.join(self.tmp, "out"))
        d = plan["runs"][0]["dir"]
        cloud = vs.read_text(os.path.join(d, "constant", "kinematicCloudProperties"))
        self.assertEqual(entry(block(cloud, "subModels"), "dispersionModel"), "stochasticDispersionRAS")
        tp = vs.read_text(os.path.join(d, "constant", "turbulenceProperties"))
        self.assertEqual(entry(tp, "simulationType"), "RAS")
        self.assertEqual(entry(block(tp, "RAS"), "RASModel"), "kOmegaSST")
        self.assertIn("meshWave", vs.read_text(os.path.join(d, "system", "fvSchemes")))
        # the same files scg reads, byte for byte, under the names the RAS model reads
        t = os.path.join(HERE, "coarse", sc["time"])
        for src, dst in (("kMean", "k"), ("omegaMean", "omega"), ("nut", "nut"), ("UMean", "U")):
            with open(os.path.join(t, src + ".gz"), "rb") as a, open(os.path.join(d, "0", dst + ".gz"), "rb") as b:
                self.assertEqual(a.read(), b.read(), src)
        self.assertTrue(os.path.isfile(os.path.join(d, "0", "alphat")))
        self.assertEqual(len(vs.internal_scalars(os.path.join(d, "0", "k.gz"))), 30819)
        # no [dispersion]: none, and the laminar model of bench/openfoam
        plan = vs.make_cases(vs.read_scene(FIXTURE), os.path.join(self.tmp, "off"))
        d = plan["runs"][0]["dir"]
        cloud = vs.read_text(os.path.join(d, "constant", "kinematicCloudProperties"))
        self.assertEqual(entry(block(cloud, "subModels"), "dispersionModel"), "none")
        self.assertFalse(os.path.exists(os.path.join(d, "0", "k.gz")))

    def test_bad_dispersion_names_the_key(self):
        base = vs.read_text(FIXTURE).replace('case = "coarse"', f'case = "{os.path.join(HERE, "coarse")}"')
        for extra, key in (('model = "langevin"\nk = "kMean"\nomega = "omegaMean"', "dispersion.model"),
                           ('model = "stochastic_ras"\nk = "kAvg"\nomega = "omegaMean"', "dispersion.k"),
                           ('model = "stochastic_ras"\nk = "kMean"', "dispersion"),
                           ('model = "stochastic_ras"\nk = "kMean"\nomega = "omegaMean"\nc0 = 2.1', "dispersion.c0")):
            with self.subTest(key=key):
                p = self.write(base + "\n[dispersion]\n" + extra + "\n")
                with self.assertRaises(vs.SceneError) as e:
                    vs.read_scene(p)
                self.assertIn(f": {key}:", str(e.exception))


class Results(unittest.TestCase):
    POST = (
        "# Time currentProc  (coordinates0 coordinates1 coordinates2 coordinates3) (position0 position1 "
        "position2) celli tetFacei tetPti facei stepFraction origProc origId active typeId nParticle d dTarget "
        "(U0 U1 U2) rho age tTurb (UTurb0 UTurb1 UTurb2)\n"
        "0.97479999999992528 0 (0 0.41 0.58 0.0007) (0.071 -0.13 1.1) 30754 88337 1 88337 0.5079 0 310 1 -1 1 "
        "1.9999999999999999e-06 0 (5.15 1.78 9.15) 2000 0.7775 0 (0 0 0)\n"
        "1.0369999999999184 0 (0 0.0006 0.65 0.34) (0.15 -0.0047 1.1) 30788 88355 1 88355 0.2429 0 789 1 -1 1 "
        "5e-06 0 (1.48 4.70 7.77) 2000 0.538 0 (0 0 0)\n"
    )

    def test_post_rows_by_column_name(self):
        rows = vs.parse_post(self.POST)
        self.assertEqual(rows, [(0.97479999999992528, 1.9999999999999999e-06, 0.7775), (1.0369999999999184, 5e-06, 0.538)])

    def test_log_counts_and_times(self):
        log = """Time = 0.0002

Evolving kinematicCloud
    Current number of parcels       = 0
    Injector d2:
      - parcels added               = 0
ExecutionTime = 0.28 s  ClockTime = 0 s

Time = 0.0004
    Current number of parcels       = 3
    Injector d2:
      - parcels added               = 2
    Injector d5:
      - parcels added               = 1
ExecutionTime = 0.30 s  ClockTime = 0 s
"""
        d = tempfile.mkdtemp()
        try:
            p = os.path.join(d, "log.foam")
            with open(p, "w") as f:
                f.write(log)
            lg = vs.parse_log(p)
        finally:
            shutil.rmtree(d)
        self.assertEqual(lg["parcels"], [0, 3])
        self.assertEqual(lg["cpu"], [0.28, 0.30])
        self.assertEqual(lg["added"], {"d2": 2, "d5": 1})

    def test_parallel_speed_and_parcels_per_rank(self):
        """Particle-steps over steps 2..N per wall second of the decomposed run, the parcels
        each processor held at the end, and an error when one held none of many."""
        log = "".join(f"    Current number of parcels = {n}\nExecutionTime = {0.1 * k:.2f} s\n"
                      for k, n in enumerate([0, 4, 6, 6]))
        d = tempfile.mkdtemp()
        try:
            with open(os.path.join(d, "log.foam"), "w") as f:
                f.write(log)
            with open(os.path.join(d, "log.foam.wall"), "w") as f:
                f.write("1.0\n1.5\n2.0\n2.5\n")

            def held(proc, n):
                p = os.path.join(d, f"processor{proc}", "0.0006", "lagrangian", vs.CLOUD)
                os.makedirs(p, exist_ok=True)
                with open(os.path.join(p, "d"), "w") as f:
                    f.write(f"FoamFile\n{{\n}}\n\n{n}\n(\n" + "2e-06\n" * n + ")\n")
            held(0, 4)
            held(1, 2)
            os.makedirs(os.path.join(d, "processor1", "0"))
            out = os.path.join(d, "np2.json")
            r = vs.parallel(out, [d], "simple (2 1 1)")
            self.assertEqual(r["particle_steps"], 16)
            self.assertAlmostEqual(r["wall_s"], 1.5)
            self.assertAlmostEqual(r["particle_steps_per_s"], 16 / 1.5)
            self.assertEqual((r["ranks"], r["parcels_per_rank_at_end"]), (2, [[4, 2]]))
            self.assertEqual(json.load(open(out))["decomposition"], "simple (2 1 1)")
            held(1, 0)
            # 4 parcels left in all: a nearly empty domain says nothing of the balance
            self.assertEqual(vs.parallel(out, [d], "simple (2 1 1)")["parcels_per_rank_at_end"], [[4, 0]])
            held(0, 40)
            with self.assertRaises(SystemExit) as e:
                vs.parallel(out, [d], "simple (2 1 1)")
            self.assertIn("held no parcel", str(e.exception))
        finally:
            shutil.rmtree(d)

    def test_table_ratios_per_core_and_on_the_machine(self):
        """Per core: scg on 1 thread against OpenFOAM's 1 process; on the machine: scg on 2
        threads against the faster of OpenFOAM's decomposed run and its serial runs at once."""
        import contextlib
        import io
        d = tempfile.mkdtemp()
        try:
            def put(name, obj):
                p = os.path.join(d, name)
                with open(p, "w") as f:
                    json.dump(obj, f)
                return p
            cls = {"group": "d1", "diameter": 1e-6, "fed": 10, "escaped": 2, "held": 8, "lost": 0,
                   "efficiency": 0.8, "residence_times": [1.0, 2.0]}
            fo = put("grade.json", {"classes": [cls], "d50": None, "particle_steps": 100,
                                    "cpu_s": 1.0, "wall_s": 1.0, "particle_steps_per_s": 1.0e6})
            grp = {"group": "d1", "diameter": 1e-6, "fed": 10, "drained": 3, "held": 7, "lost": 0}
            s1 = put("s1.json", {"groups": [grp], "threads": 1, "particle_steps": 100, "wall_s": 1.0,
                                 "particle_steps_per_s": 2.0e6})
            s2 = put("s2.json", {"groups": [grp], "threads": 2, "particle_steps": 100, "wall_s": 1.0,
                                 "particle_steps_per_s": 3.6e6})
            fp = put("np2.json", {"ranks": 2, "decomposition": "simple (2 1 1)", "particle_steps": 100,
                                  "wall_s": 1.0, "particle_steps_per_s": 0.8e6,
                                  "parcels_per_rank_at_end": [[5, 3]]})
            fc = put("twice.json", {"processes": 2, "particle_steps_per_s": 1.8e6,
                                    "runs": [{"wall_s": 1.0}, {"wall_s": 1.1}]})
            out = io.StringIO()
            with contextlib.redirect_stdout(out):
                vs.table(fo, s1, s2, fp, fc)
            lines = out.getvalue().splitlines()
            self.assertIn("speed ratio per core (scg 1 thread / OpenFOAM 1 process, CPU): 2.00", lines)
            self.assertEqual(lines[-1], "speed ratio, the machine's 2 cores (scg 2 threads / OpenFOAM's "
                                        "faster use of them, serial runs at once): 2.00")
            self.assertTrue(any("-10.00" in ln for ln in lines), lines)
        finally:
            shutil.rmtree(d)

    def test_d50_interpolates_in_log_d(self):
        cls = [{"diameter": 2e-6, "efficiency": 0.2}, {"diameter": 8e-6, "efficiency": 0.8},
               {"diameter": 20e-6, "efficiency": 1.0}]
        self.assertAlmostEqual(vs.d50(cls), 4e-6, delta=1e-18)
        self.assertIsNone(vs.d50([{"diameter": 2e-6, "efficiency": 0.7}, {"diameter": 5e-6, "efficiency": 0.9}]))

    def test_sampling_sigma(self):
        # two classes of 400 at 0.75: sqrt(2 * 0.1875 / 400) = 3.06 pp
        self.assertAlmostEqual(vs.sampling_pp(400, 0.75, 400, 0.75), 100 * (2 * 0.1875 / 400) ** 0.5)
        self.assertEqual(vs.sampling_pp(400, 1.0, 400, 1.0), 0.0)


class LikeForLike(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp()

    def tearDown(self):
        shutil.rmtree(self.tmp)

    def test_the_scene_loses_what_openfoam_cannot_run_and_nothing_else(self):
        import tomllib
        src = os.path.join(HERE, "..", "cyclone.toml")
        with open(src, "rb") as f:
            orig = tomllib.load(f)
        # TOML written back reads as the same dict
        self.assertEqual(tomllib.loads(vs.toml_dump(orig)), orig)
        # the committed scene as is: refused, naming the key
        with self.assertRaises(vs.SceneError) as e:
            vs.read_scene(src)
        self.assertIn("zones.0.collects", str(e.exception))
        dest = os.path.join(self.tmp, "scene.toml")
        changes = vs.like(src, dest)
        # the conservative interpolation alone is refused too
        cons = os.path.join(self.tmp, "cons.toml")
        with open(dest, encoding="utf-8") as f:
            text = f.read().replace('interpolation = "cell_point_idw"', 'interpolation = "conservative"')
        with open(cons, "w", encoding="utf-8") as f:
            f.write(text)
        with self.assertRaises(vs.SceneError) as e:
            vs.read_scene(cons)
        self.assertIn("flow.interpolation", str(e.exception))
        self.assertEqual(len(changes), 3, changes)
        self.assertTrue(changes[0].startswith("flow.interpolation: conservative -> cell_point_idw"), changes)
        self.assertTrue(changes[1].startswith("dispersion.model: langevin -> stochastic_ras"), changes)
        self.assertTrue(changes[2].startswith("zones[0]"), changes)
        with open(dest, "rb") as f:
            got = tomllib.load(f)
        self.assertNotIn("wall_function", got["flow"])
        self.assertEqual(got["flow"]["interpolation"], "cell_point_idw")
        self.assertEqual(got["dispersion"]["model"], "stochastic_ras")
        # a wall function goes too
        wfs = os.path.join(self.tmp, "wf.toml")
        with open(src, encoding="utf-8") as f:
            text = f.read().replace('interpolation = "conservative"',
                                    'interpolation = "cell_point"\n[flow.wall_function]\n'
                                    'model = "log_law"\nk = "kMean"\n#', 1)
        self.assertIn("log_law", text)
        with open(wfs, "w", encoding="utf-8") as f:
            f.write(text)
        wf_changes = vs.like(wfs, os.path.join(self.tmp, "wf-like.toml"))
        self.assertTrue(wf_changes[0].startswith("flow.wall_function"), wf_changes)
        self.assertEqual([z.get("collects", False) for z in got["zones"]], [False, False])
        # the scene's waiting trap (collects_after) goes with it
        self.assertIn("collects_after", orig["zones"][0])
        self.assertNotIn("collects_after", got["zones"][0])
        self.assertTrue(os.path.isabs(got["flow"]["case"]) and os.path.isdir(got["flow"]["case"]))
        # everything else as it was: dispersion fields, walls, feeders, groups
        # (the Langevin walk's own c0 goes with it: stochastic_ras refuses it)
        self.assertIn("c0", orig["dispersion"])
        self.assertNotIn("c0", got["dispersion"])
        self.assertEqual({k: v for k, v in got["dispersion"].items() if k != "model"},
                         {k: v for k, v in orig["dispersion"].items() if k not in ("model", "c0")})
        for k in ("groups", "feeders", "drag", "gravity", "material", "fluid", "dt", "duration"):
            self.assertEqual(got[k], orig[k], k)
        self.assertEqual(got["flow"]["patches"], orig["flow"]["patches"])
        sc = vs.read_scene(dest)
        self.assertEqual(sc["dispersion"]["model"], "stochastic_ras")
        self.assertEqual(len(sc["classes"]), 10)
        # a collecting zone alone is refused too
        zone = os.path.join(self.tmp, "zone.toml")
        with open(FIXTURE) as f:
            text = f.read()
        with open(zone, "w") as f:
            f.write(text.replace('case = "coarse"', f'case = "{os.path.join(HERE, "coarse")}"')
                    + '\n[[zones]]\nname = "bin"\ncollects = true\nregion = { kind = "box", min = [0.0, 0.0, 0.0], max = [1.0, 1.0, 1.0] }\n')
        with self.assertRaises(vs.SceneError) as e:
            vs.read_scene(zone)
        self.assertIn("zones.0.collects", str(e.exception))
        # nothing to change: no line, the same dict
        plain = os.path.join(self.tmp, "plain.toml")
        self.assertEqual(vs.like(dest, plain), [])

    def test_friction_takes_openfoams_rebound_rule(self):
        """A rebound with friction > 0: read_scene refuses scg's Coulomb impact (another
        model under OpenFOAM's mu), `like` switches it to friction_model =
        "openfoam_fraction" in [flow.patches] and in each per-patch table with friction."""
        import tomllib
        src = os.path.join(self.tmp, "mu.toml")
        with open(FIXTURE) as f:
            text = f.read().replace('case = "coarse"', f'case = "{os.path.join(HERE, "coarse")}"')
        self.assertIn("[flow.patches]", text)
        text = text.replace("[flow.patches]", "[flow.patches]\nfriction = 0.3", 1)
        with open(src, "w") as f:
            f.write(text)
        with self.assertRaises(vs.SceneError) as e:
            vs.read_scene(src)
        self.assertIn("flow.patches.friction_model", str(e.exception))
        dest = os.path.join(self.tmp, "mu-like.toml")
        changes = vs.like(src, dest)
        self.assertIn("flow.patches.friction_model", [c.split(":")[0] for c in changes], changes)
        with open(dest, "rb") as f:
            got = tomllib.load(f)
        self.assertEqual(got["flow"]["patches"]["friction_model"], "openfoam_fraction")
        sc = vs.read_scene(dest)
        self.assertTrue(all(i["friction_model"] == "openfoam_fraction" for i in sc["interaction"].values()))
        # the rule's own name is kept, and a frictionless scene is left alone
        self.assertEqual(vs.like(dest, os.path.join(self.tmp, "again.toml")), [])


if __name__ == "__main__":
    unittest.main()
