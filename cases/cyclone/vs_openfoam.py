"""Helpers of cases/cyclone/vs-openfoam.sh: the cyclone scene side by side with OpenFOAM's
particle tracker (uncoupledKinematicParcelFoam, v1912). Python 3.11+ standard library;
bench/foam.py's helpers (dictionary header, timed run, list reader) are imported.

  python3 vs_openfoam.py case SCENE DIR [--duration T] [--feed-scale F] [--dt DT]
      OpenFOAM case(s) under DIR from the scg scene SCENE: one case per particle density
      (one kinematic cloud has one rho0), DIR/rho<ρ>/, and DIR/plan.json (the classes and
      the runs). The scene's flow field (flow.case, flow.time, flow.field) is the frozen U;
      with [dispersion] model = "stochastic_ras" the scene's k and omega (or epsilon) fields
      of the same time folder are the frozen k and omega (epsilon) of a RAS model that is
      constructed and never solved, and the cloud's dispersionModel is
      stochasticDispersionRAS (below)
  python3 vs_openfoam.py like SCENE OUT.toml
      the scene as both codes run it side by side, written to OUT.toml (one line printed per
      change): what OpenFOAM's tracker has no model for is switched off in scg too — the
      log-law wall function ([flow.wall_function], scg-only: OpenFOAM interpolates to the
      walls' no-slip values) and collecting zones ([[zones]] collects, a trap OpenFOAM's
      cloud has not: both then count 1 - escaped/fed) —, cell_point and conservative
      interpolation become cell_point_idw (OpenFOAM's cellPoint point values), langevin
      dispersion becomes stochastic_ras (the eddy model OpenFOAM's tracker has), a
      rebound with friction > 0 takes friction_model = "openfoam_fraction" (OpenFOAM's
      rebound rule), and flow.case is made absolute
  python3 vs_openfoam.py grade DIR OUT.json
      reads each run's log and patchPostProcessing output and writes grade.json
  python3 vs_openfoam.py summary GRADE.json [PARALLEL.json [CONCURRENT.json]]
      OpenFOAM's side alone (vs-openfoam.sh --openfoam-only): per class fed, escaped,
      held, lost, efficiency, and the speeds
  python3 vs_openfoam.py parallel OUT.json DECOMPOSITION DIR...
      the speed of the decomposed runs DIR... (mpirun -np N ... -parallel): particle-steps
      per wall second, parcels per processor at the end (an error if one held none)
  python3 vs_openfoam.py concurrent OUT.json DIR...
      the summed speed of serial runs started together (one per core)
  python3 vs_openfoam.py table GRADE.json SCG1.json SCG2.json [PARALLEL.json [CONCURRENT.json]]
      the side-by-side table (scg's `run --summary-json` on 1 and 2 threads; OpenFOAM on
      1 process, on N ranks and as serial runs at once when given) and the speed ratios:
      per core, and on the machine's cores (against OpenFOAM's faster use of them)

Patch interaction, from [flow.patches]: wall_model "rebound" with [material] restitution and
no friction (the cyclone scenes) -> standardWallInteraction rebound (e, mu 0); wall_model
"stick" | "escape" | "rebound" (restitution, friction) and [flow.patches.interaction]
per-patch tables -> localInteraction, one entry per patch (outlets, inlets and unlisted
non-wall patches escape). OpenFOAM's rebound removes the fraction mu of the tangential
velocity (U -= mu*Ut): a rebound with friction > 0 must say friction_model =
"openfoam_fraction" (scg's same rule), else the scene is refused (scg's default Coulomb
impact is another model under the same number). grade.json per class: fed, escaped (outlets), lost (other escape
patches), stuck (written inactive at the end), held (written active), patches (counts by
patch), and the log's localInteraction per-patch totals (log_fates).

Turbulent dispersion, from [dispersion] (absent or model = "none": dispersionModel none):
model = "stochastic_ras" -> dispersionModel stochasticDispersionRAS; the fields named by
k (default "k") and omega, or epsilon, in the flow's time folder are copied as 0/k and
0/omega (0/epsilon) — the same files scg reads, whatever their names (kMean, omegaMean) —
with constant/turbulenceProperties RAS kOmegaSST (kEpsilon with epsilon), whose epsilon()
is betaStar k omega, betaStar = 0.09 (printCoeffs in the log); 0/nut (the time folder's
nut, else uniform 0), 0/alphat (uniform 0: the compressible model's EddyDiffusivity reads
it) and fvSchemes' wallDist (the SST model's wall distance) for its constructor.
uncoupledKinematicParcelFoam constructs the turbulence model but never calls its correct():
k and omega stay the files' values (grade checks the k and omega it writes at the end
against the inputs). The dispersion model takes k and epsilon of the parcel's cell (cell
values, no interpolation).

Exit status 2 (message naming the file and key) when the scene cannot be mapped.
"""
import gzip
import json
import math
import os
import re
import shutil
import sys
import tomllib

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "bench"))
import foam  # noqa: E402  (bench/foam.py: header, foam_list, run)

CLOUD = "kinematicCloud"
PPP = "patchPostProcessing1"
R_UNIVERSAL = 8314.47    # J/(kmol K), OpenFOAM's thermodynamic constant RR (v1912)
MOL_WEIGHT = 28.96       # kg/kmol, air
P_REF = 1.0e5            # Pa; T is chosen so that p/(R T) is the scene's fluid density


class SceneError(Exception):
    pass


def read_text(path):
    with open(path) as f:
        return f.read()


def read_json(path):
    with open(path) as f:
        return json.load(f)


def bad(path, key, msg):
    raise SceneError(f"{path}: {key}: {msg}")


# scg's rebound friction models ([flow.patches] friction_model): OpenFOAM's is "openfoam_fraction"
FRICTION_MODELS = ("coulomb", "openfoam_fraction")


def read_toml(path):
    try:
        with open(path, "rb") as f:
            return tomllib.load(f)
    except (OSError, tomllib.TOMLDecodeError) as e:
        raise SceneError(f"{path}: {e}")


def read_scene(path, duration=None, feed_scale=None, dt=None):
    """The comparison's settings from an scg scene (dict). Classes: one per [[groups]],
    each fed by exactly one [[feeders]] with `patch`. A scene with what OpenFOAM's tracker
    cannot run (a wall function, a collecting zone) is refused: `like` writes the scene
    without them."""
    s = read_toml(path)
    wf = s.get("flow", {}).get("wall_function", {})
    if wf.get("model", "none") != "none":
        bad(path, "flow.wall_function.model", f"{wf.get('model')!r} has no OpenFOAM counterpart "
            "(vs_openfoam.py like writes the scene without it)")
    for i, z in enumerate(s.get("zones", [])):
        if z.get("collects"):
            bad(path, f"zones.{i}.collects", "OpenFOAM's cloud has no trap zone "
                "(vs_openfoam.py like writes the scene without it)")
    base = os.path.dirname(os.path.abspath(path))
    if feed_scale is None:  # as scg's --set feed_scale=F: replaces the scene's
        feed_scale = float(s.get("feed_scale", 1.0))
    flow = s.get("flow", {})
    if flow.get("kind") != "openfoam":
        bad(path, "flow.kind", 'must be "openfoam"')
    case = os.path.normpath(os.path.join(base, flow.get("case", "")))
    if not os.path.isdir(os.path.join(case, "constant", "polyMesh")):
        bad(path, "flow.case", f"no constant/polyMesh in {case}")
    if float(flow.get("scale", 1.0)) != 1.0:
        bad(path, "flow.scale", "only 1.0 (a mesh in metres) is supported")
    field = flow.get("field", "U")
    time = flow.get("time", "latest")
    times = sorted((d for d in os.listdir(case) if re.fullmatch(r"[0-9.eE+-]+", d)
                    and os.path.isdir(os.path.join(case, d))), key=float)
    if time == "latest":
        if not times:
            bad(path, "flow.time", f"no time folder in {case}")
        time = times[-1]
    else:
        time = next((t for t in times if float(t) == float(time)), None)
        if time is None:
            bad(path, "flow.time", f"{flow.get('time')} not among {times} in {case}")
    field_file = next((os.path.join(case, time, field + ext) for ext in (".gz", "")
                       if os.path.isfile(os.path.join(case, time, field + ext))), None)
    if field_file is None:
        bad(path, "flow.field", f"no {field} in {os.path.join(case, time)}")
    patches = flow.get("patches", {})
    walls = list(patches.get("walls", []))
    outlets = list(patches.get("outlets", []))
    inlets = list(patches.get("inlets", []))
    # What each patch does to a particle (OpenFOAM's patch interaction): the wall patches
    # by flow.patches.wall_model, outlets and inlets escape, [flow.patches.interaction]
    # overrides per patch. Rebound: restitution (flow.patches, else [material]) and friction.
    wall_model = patches.get("wall_model", "rebound")
    if wall_model not in ("rebound", "stick", "escape"):
        bad(path, "flow.patches.wall_model", f'{wall_model!r}: must be "rebound", "stick" or "escape" '
            '(OpenFOAM: standardWallInteraction rebound or localInteraction; "contact" has no counterpart)')
    restitution = float(patches.get("restitution", s.get("material", {}).get("restitution", 1.0)))
    friction = float(patches.get("friction", 0.0))

    def friction_rule(key, value):
        if value not in FRICTION_MODELS:
            bad(path, key, f'{value!r}: must be "coulomb" or "openfoam_fraction"')
        return value

    friction_model = friction_rule("flow.patches.friction_model", patches.get("friction_model", "coulomb"))
    interaction = {}
    for p in walls:
        interaction[p] = {"model": wall_model, "e": restitution, "mu": friction,
                          "friction_model": friction_model}
    for p in outlets + inlets:
        interaction[p] = {"model": "escape", "e": restitution, "mu": friction,
                          "friction_model": friction_model}
    overrides = patches.get("interaction", {})
    if not isinstance(overrides, dict):
        bad(path, "flow.patches.interaction", "a table of patch = { model = ... }")
    for p, o in overrides.items():
        key = f"flow.patches.interaction.{p}"
        if not isinstance(o, dict):
            bad(path, key, 'needs { model = "stick" | "escape" | "rebound", ... }')
        model = o.get("model")
        if model not in ("rebound", "stick", "escape"):
            bad(path, key + ".model", f'{model!r}: must be "rebound", "stick" or "escape"')
        fm = friction_rule(key + ".friction_model", o.get("friction_model", friction_model))
        interaction[p] = {"model": model, "e": float(o.get("restitution", restitution)),
                          "mu": float(o.get("friction", friction)), "friction_model": fm}
    # OpenFOAM's rebound removes the fraction mu of the tangential velocity (U -= mu*Ut);
    # scg's "coulomb" friction is another model under the same number: refused unless 0
    for p, i in interaction.items():
        if i["model"] == "rebound" and i["mu"] > 0.0 and i["friction_model"] != "openfoam_fraction":
            key = (f"flow.patches.interaction.{p}" if p in overrides else "flow.patches")
            bad(path, key + ".friction_model",
                f"friction {i['mu']} with the Coulomb impact (scg's default) is not OpenFOAM's rebound, "
                "which removes the fraction mu of the tangential velocity (U -= mu*Ut): set "
                'friction_model = "openfoam_fraction" (vs_openfoam.py like does)')
    fluid = s.get("fluid", {})
    rho_f = float(fluid.get("density", 1.2))
    mu = float(fluid.get("viscosity", 1.8e-5))
    g = [float(x) for x in s.get("gravity", {}).get("acceleration", [0.0, 0.0, 0.0])]
    if len(g) != 3:
        bad(path, "gravity.acceleration", "needs 3 components")
    dt = s.get("dt") if dt is None else dt
    if not isinstance(dt, (int, float)) or dt <= 0:
        bad(path, "dt", "a fixed time step (s) is needed")
    dur = float(duration if duration is not None else s.get("duration", 0.0))
    if dur <= 0:
        bad(path, "duration", "must be positive")
    dispersion = read_dispersion(path, s.get("dispersion", {}), case, time)
    interp = flow.get("interpolation", "cell_point")
    foam_interp = {"cell_value": "cell", "cell_point": "cellPoint", "cell_point_idw": "cellPoint"}.get(interp)
    if foam_interp is None:
        bad(path, "flow.interpolation", f"{interp!r} has no OpenFOAM counterpart")
    groups = s.get("groups", [])
    if not groups:
        bad(path, "groups", "no [[groups]]")
    feeders = s.get("feeders", [])
    classes = []
    for i, gr in enumerate(groups):
        name = gr.get("name")
        fs = [(j, f) for j, f in enumerate(feeders) if f.get("group") == name]
        if len(fs) != 1:
            bad(path, f"groups.{i}", f"group {name!r} needs exactly one [[feeders]] (has {len(fs)})")
        j, f = fs[0]
        if "patch" not in f:
            bad(path, f"feeders.{j}.patch", "the comparison feeds through a patch (patchInjection)")
        v = f.get("velocity")
        if not (isinstance(v, list) and len(v) == 3):
            bad(path, f"feeders.{j}.velocity", "needs a vector (OpenFOAM's U0)")
        if f.get("weight", "area") != "area":
            bad(path, f"feeders.{j}.weight", f"{f.get('weight')!r}: OpenFOAM's patchInjection "
                "places parcels uniformly by area")
        if float(gr.get("alpha", 1.0)) != 1.0:
            bad(path, f"groups.{i}.alpha", "the comparison is of the original particles (alpha = 1)")
        start = float(f.get("start", 0.0))
        stop = min(float(f.get("stop", dur)), dur)
        classes.append({
            "group": name, "diameter": float(gr["diameter"]), "density": float(gr["density"]),
            "patch": f["patch"], "rate": float(f["rate"]) * feed_scale,
            "start": start, "stop": stop, "velocity": [float(x) for x in v],
        })
    erosion = None
    if "erosion" in s:
        e = s["erosion"]
        if e.get("model") != "finnie":
            bad(path, "erosion.model", f"{e.get('model')!r}: OpenFOAM's ParticleErosion is Finnie's")
        ep = list(e.get("patches", [p for p in walls if interaction[p]["model"] in ("rebound", "stick")]))
        erosion = {"p": float(e["flow_stress"]), "psi": float(e.get("psi", 2.0)),
                   "K": float(e.get("k", 2.0)), "patches": ep}
    return {
        "scene": os.path.abspath(path), "name": s.get("name", "scene"), "erosion": erosion,
        "case": case, "time": time, "field": field, "field_file": field_file,
        "interpolation": interp, "foam_interpolation": foam_interp,
        "walls": walls, "outlets": outlets, "inlets": inlets, "restitution": restitution,
        "friction": friction, "wall_model": wall_model, "interaction": interaction,
        "interaction_table": bool(overrides),
        "rho_f": rho_f, "mu": mu, "gravity": g, "dt": float(dt), "duration": dur,
        "drag": s.get("drag", {}).get("law", "stokes"), "classes": classes,
        "feed_scale": feed_scale, "dispersion": dispersion,
    }


def toml_key(k):
    return k if re.fullmatch(r"[A-Za-z0-9_-]+", k) else json.dumps(k)


def toml_value(v):
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        if isinstance(v, float) and not math.isfinite(v):
            raise ValueError(f"{v} has no TOML form here")
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v, ensure_ascii=False)
    if isinstance(v, list):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{toml_key(k)} = {toml_value(x)}" for k, x in v.items()) + " }"
    raise ValueError(f"{v!r} has no TOML form here")


def toml_dump(d):
    """TOML text of a dict as tomllib reads it (tables, arrays of tables, inline values);
    tomllib.loads(toml_dump(d)) == d."""
    out = []

    def is_aot(v):
        return isinstance(v, list) and v and all(isinstance(x, dict) for x in v)

    def body(prefix, t):
        for k, v in t.items():
            if not isinstance(v, dict) and not is_aot(v):
                out.append(f"{toml_key(k)} = {toml_value(v)}")
        for k, v in t.items():
            name = f"{prefix}.{toml_key(k)}" if prefix else toml_key(k)
            if isinstance(v, dict):
                out.append(f"\n[{name}]")
                body(name, v)
        for k, v in t.items():
            name = f"{prefix}.{toml_key(k)}" if prefix else toml_key(k)
            if is_aot(v):
                for x in v:
                    out.append(f"\n[[{name}]]")
                    for kk, vv in x.items():
                        out.append(f"{toml_key(kk)} = {toml_value(vv)}")

    body("", d)
    return "\n".join(out) + "\n"


def like(path, dest):
    """The scene of `path` as both codes run it side by side, written to `dest`; returns
    one line per change (see the module's doc)."""
    s = read_toml(path)
    changes = []
    flow = s.get("flow", {})
    wf = flow.get("wall_function")
    if wf is not None and wf.get("model", "none") != "none":
        del flow["wall_function"]
        changes.append(f"flow.wall_function: model {wf.get('model')!r} off (OpenFOAM's tracker "
                       "interpolates to the walls' no-slip values; scg does the same)")
    interp = flow.get("interpolation", "cell_point")
    if flow.get("kind") == "openfoam" and interp in ("cell_point", "conservative"):
        flow["interpolation"] = "cell_point_idw"
        changes.append(f"flow.interpolation: {interp} -> cell_point_idw (OpenFOAM's cellPoint: "
                       "its inverse-distance point values)")
    d = s.get("dispersion")
    if isinstance(d, dict) and d.get("model") == "langevin":
        d["model"] = "stochastic_ras"
        for key in ("c0", "csanady"):  # the Langevin walk's own parameters
            d.pop(key, None)
        changes.append("dispersion.model: langevin -> stochastic_ras (OpenFOAM's "
                       "stochasticDispersionRAS, the eddy model its tracker has)")
    patches = flow.get("patches", {})
    if isinstance(patches, dict):
        tables = [("flow.patches", patches)] + [
            (f"flow.patches.interaction.{p}", o)
            for p, o in (patches.get("interaction") or {}).items() if isinstance(o, dict)]
        for key, t in tables:
            fm = t.get("friction_model", patches.get("friction_model", "coulomb"))
            mu = float(t.get("friction", patches.get("friction", 0.0)))
            if mu > 0.0 and fm != "openfoam_fraction":
                t["friction_model"] = "openfoam_fraction"
                changes.append(f"{key}.friction_model: {fm} -> openfoam_fraction (OpenFOAM's "
                               f"rebound: the fraction mu = {mu:g} of the tangential velocity removed)")
    for i, z in enumerate(s.get("zones", [])):
        if z.get("collects"):
            z["collects"] = False
            z.pop("collects_after", None)
            changes.append(f"zones[{i}] ({z.get('name')}): collects off (OpenFOAM's cloud has "
                           "no trap zone; both codes count 1 - escaped/fed)")
    if "case" in flow and not os.path.isabs(flow["case"]):
        flow["case"] = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(path)), flow["case"]))
    with open(dest, "w", encoding="utf-8") as f:
        f.write(f"# {os.path.abspath(path)} as scg and OpenFOAM both run it "
                "(cases/cyclone/vs_openfoam.py like)\n")
        for c in changes:
            f.write(f"# {c}\n")
        f.write(toml_dump(s))
    return changes


def time_file(case, time, name):
    """The field `name` of time folder `time` of `case` (name.gz or name), or None."""
    return next((os.path.join(case, time, name + ext) for ext in (".gz", "")
                 if os.path.isfile(os.path.join(case, time, name + ext))), None)


DISPERSION_KEYS = ("model", "k", "omega", "epsilon")


def read_dispersion(path, d, case, time):
    """[dispersion] of the scene: None (no dispersion) or the model and the turbulence
    fields' files: {"model", "foam_model", "ras_model", "k", "k_file", "second",
    "second_name", "second_file"} with second "omega" (kOmegaSST) or "epsilon" (kEpsilon)."""
    if not isinstance(d, dict):
        bad(path, "dispersion", "a table")
    model = d.get("model", "none")
    if model == "none":
        return None
    if model != "stochastic_ras":
        bad(path, "dispersion.model", f'{model!r}: only "stochastic_ras" (OpenFOAM\'s stochasticDispersionRAS) '
            'or "none" have an OpenFOAM counterpart')
    for key in d:
        if key not in DISPERSION_KEYS:
            bad(path, f"dispersion.{key}", f"not mapped to OpenFOAM (keys: {', '.join(DISPERSION_KEYS)})")
    if "omega" in d and "epsilon" in d:
        bad(path, "dispersion", "give omega or epsilon, not both")
    if "omega" not in d and "epsilon" not in d:
        bad(path, "dispersion", "needs omega = FIELD or epsilon = FIELD (a field of the flow's time folder)")
    second = "omega" if "omega" in d else "epsilon"
    out = {"model": model, "foam_model": "stochasticDispersionRAS", "second": second,
           "ras_model": "kOmegaSST" if second == "omega" else "kEpsilon"}
    for key, name in (("k", d.get("k", "k")), (second, d[second])):
        if not isinstance(name, str) or not name:
            bad(path, f"dispersion.{key}", "a field name")
        f = time_file(case, time, name)
        if f is None:
            bad(path, f"dispersion.{key}", f"no {name} in {os.path.join(case, time)}")
        if key == "k":
            out["k"], out["k_file"] = name, f
        else:
            out["second_name"], out["second_file"] = name, f
    out["nut_file"] = time_file(case, time, "nut")
    return out


def boundary_types(case):
    """{patch: type} from constant/polyMesh/boundary(.gz)."""
    p = os.path.join(case, "constant", "polyMesh", "boundary")
    if os.path.isfile(p + ".gz"):
        with gzip.open(p + ".gz", "rt") as f:
            text = f.read()
    else:
        text = read_text(p)
    body = text[text.index("(", text.index("FoamFile") + 10):]
    return dict(re.findall(r"(\w+)\s*\{[^}]*?type\s+(\w+);", body))


def g6(x):
    return repr(float(x))


def patch_interactions(sc):
    """{patch: {"model", "e", "mu"}} for every patch of the mesh (sc["boundary"]): the
    scene's, and "escape" for a non-wall patch the scene does not list (what scg does
    with it and OpenFOAM's default)."""
    out = {}
    for p in sc["boundary"]:
        out[p] = dict(sc["interaction"].get(p) or {"model": "escape", "e": sc["restitution"], "mu": sc["friction"]})
    return out


def standard_wall(sc):
    """True when OpenFOAM's standardWallInteraction says what the scene says: every wall
    patch rebounds with one restitution and no friction, every other patch lets particles
    escape, and no per-patch table is given (the cyclone scenes); localInteraction else."""
    if sc.get("interaction_table") or sc.get("wall_model", "rebound") != "rebound" or sc.get("friction", 0.0):
        return False
    for p, i in patch_interactions(sc).items():
        want = "rebound" if sc["boundary"][p] == "wall" else "escape"
        if i["model"] != want or (want == "rebound" and (i["e"] != sc["restitution"] or i["mu"] != 0.0)):
            return False
    return True


def fate_patches(sc):
    """The patches where a particle's fate is decided (escape or stick): the ones
    patchPostProcessing records."""
    if standard_wall(sc):
        return sorted(set(sc["outlets"]) | set(p for p in sc["boundary"] if sc["boundary"][p] != "wall"))
    return sorted(p for p, i in patch_interactions(sc).items() if i["model"] in ("escape", "stick"))


def interaction_text(sc):
    """The cloud's patchInteractionModel and its coefficients."""
    if standard_wall(sc):
        return f"""patchInteractionModel standardWallInteraction;

    standardWallInteractionCoeffs
    {{
        type rebound;           // wall patches: v_n' = -e v_n, v_t' = (1 - mu) v_t
        e    {g6(sc['restitution'])};
        mu   0;
    }}
    // A parcel reaching a patch that is not of type wall escapes (leaves the cloud)."""
    rows = []
    for p, i in sorted(patch_interactions(sc).items()):
        if i["model"] == "rebound":
            rows.append(f"            {p} {{ type rebound; e {g6(i['e'])}; mu {g6(i['mu'])}; }}")
        else:
            rows.append(f"            {p} {{ type {i['model']}; }}")
    return f"""patchInteractionModel localInteraction;

    // scene [flow.patches]: stick = the parcel stays where it hit (inactive, U = 0);
    // escape = it leaves the cloud; rebound: v_n' = -e v_n, v_t' = (1 - mu) v_t
    localInteractionCoeffs
    {{
        patches
        (
{chr(10).join(rows)}
        );
    }}"""


def injection_duration(c, dt):
    """patchInjection's `duration` for class c. It injects in every step whose start,
    relative to SOI, is below the duration; the accumulated times fall a hair short of
    whole multiples of dt, so a window of exactly N steps gets an (N+1)th step. When
    whole parcels come each step (rate * dt >= 1: OpenFOAM then adds floor(rate * dt),
    one more with the remainder's probability) that step would add them again (505 for
    scg's 500): the window is then given as N - 1/2 steps. Below one per step OpenFOAM
    holds the time until a parcel is due and the window is left as it is."""
    w = c["stop"] - c["start"]
    n = w / dt
    if c["rate"] * dt >= 1.0 and round(n) >= 1 and abs(n - round(n)) < 1e-6:
        return (round(n) - 0.5) * dt
    return w


def cloud_properties(sc, classes, rho_p):
    inj = []
    for k, c in enumerate(classes):
        inj.append(f"""        {c['group']}
        {{
            type            patchInjection;
            patch           {c['patch']};
            SOI             {g6(c['start'])};
            duration        {g6(injection_duration(c, sc['dt']))};
            parcelsPerSecond {g6(c['rate'])};
            massTotal       0;
            parcelBasisType fixed;
            nParticle       1;              // one particle per parcel
            U0              ({' '.join(g6(x) for x in c['velocity'])});
            flowRateProfile constant 1;     // not used with parcelBasisType fixed
            sizeDistribution
            {{
                type        fixedValue;
                fixedValueDistribution {{ value {g6(c['diameter'])}; }}
            }}
        }}""")
    patches = fate_patches(sc)
    interp = sc["foam_interpolation"]
    return foam.header("dictionary", "constant", "kinematicCloudProperties") + f"""\
// scg vs-openfoam.sh (cases/cyclone/vs_openfoam.py) from {os.path.basename(sc['scene'])}: classes {', '.join(c['group'] for c in classes)}
solution
{{
    active          true;
    coupled         false;      // one-way: the flow is frozen
    transient       yes;
    cellValueSourceCorrection off;
    maxCo           1;

    interpolationSchemes
    {{
        rho             cell;
        U               {interp};
        mu              cell;
        thermo:mu       cell;
    }}

    integrationSchemes
    {{
        U               analytical;
    }}

    sourceTerms
    {{
        schemes
        {{
        }}
    }}
}}

constantProperties
{{
    rho0            {g6(rho_p)};
    youngsModulus   1e8;        // unused (no collision model)
    poissonsRatio   0.35;
    constantVolume  false;
}}

subModels
{{
    particleForces
    {{
        sphereDrag;             // Cd = 24/Re (1 + Re^(2/3)/6)
        gravity;
    }}

    injectionModels
    {{
{chr(10).join(inj)}
    }}

    dispersionModel {dispersion_model(sc)};

    {interaction_text(sc)}

    heatTransferModel none;
    surfaceFilmModel none;
    collisionModel none;
    stochasticCollisionModel none;
    radiation off;
}}

cloudFunctions
{{
    {PPP}
    {{
        type            patchPostProcessing;
        maxStoredParcels 100000000;
        patches         ({' '.join(patches)});
    }}
{erosion_function(sc)}}}
"""


def erosion_function(sc):
    """OpenFOAM's ParticleErosion (Finnie) as the scene's [erosion] declares it, or nothing."""
    e = sc.get("erosion")
    if not e:
        return ""
    return f"""    particleErosion1
    {{
        type            particleErosion;
        patches         ({' '.join(e['patches'])});
        p               {g6(e['p'])};
        psi             {g6(e['psi'])};
        K               {g6(e['K'])};
    }}
"""


def dispersion_model(sc):
    d = sc.get("dispersion")
    if d is None:
        return "none"
    return (f"{d['foam_model']};   // scene [dispersion] model = \"{d['model']}\": k = {d['k']}, "
            f"{d['second']} = {d['second_name']} (constant/turbulenceProperties)")


def turbulence_files(sc):
    """{relative path: text} of the frozen RAS model's dictionaries and generated fields
    (the k and omega/epsilon files are copied by make_cases)."""
    d = sc["dispersion"]
    tp = foam.header("dictionary", "constant", "turbulenceProperties") + f"""\
// scg vs-openfoam.sh: the RAS model whose k() and epsilon() the cloud's
// stochasticDispersionRAS reads. uncoupledKinematicParcelFoam constructs it (reading 0/k,
// 0/{d['second']}, 0/nut, 0/alphat) and never solves it: k = the scene's {d['k']},
// {d['second']} = the scene's {d['second_name']}{'; epsilon() = betaStar k omega' if d['second'] == 'omega' else ''}.
simulationType  RAS;
RAS
{{
    RASModel        {d['ras_model']};
    turbulence      on;
    printCoeffs     on;
}}
"""
    scalar = lambda name, dim: foam.header("volScalarField", "0", name) + (
        f"dimensions      {dim};\ninternalField   uniform 0;\n"
        'boundaryField\n{\n    ".*" { type calculated; value uniform 0; }\n}\n')
    files = {"constant/turbulenceProperties": tp,
             "0/alphat": scalar("alphat", "[1 -1 -1 0 0 0 0]")}
    if d.get("nut_file") is None:
        files["0/nut"] = scalar("nut", "[0 2 -1 0 0 0 0]")
    schemes = read_text(os.path.join(HERE, "..", "..", "bench", "openfoam", "system", "fvSchemes"))
    files["system/fvSchemes"] = schemes + "wallDist        { method meshWave; }   // the RAS model's wall distance\n"
    return files


def control_dict(sc):
    steps = round(sc["duration"] / sc["dt"])
    return foam.header("dictionary", "system", "controlDict") + f"""\
application     uncoupledKinematicParcelFoam;
startFrom       startTime;
startTime       0;
stopAt          endTime;
endTime         {g6(steps * sc['dt'])};
deltaT          {g6(sc['dt'])};
adjustTimeStep  no;             // the scene's fixed dt (the solver adjusts it otherwise)
maxCo           1;
maxDeltaT       {g6(sc['dt'])};
writeControl    timeStep;       // written once, at the end
writeInterval   {steps};
purgeWrite      0;
writeFormat     ascii;
writePrecision  17;
writeCompression off;
timeFormat      general;
timePrecision   12;
runTimeModifiable no;
"""


def thermo(sc):
    r = R_UNIVERSAL / MOL_WEIGHT
    t = P_REF / (sc["rho_f"] * r)
    th = foam.header("dictionary", "constant", "thermophysicalProperties") + f"""\
thermoType
{{
    type            hePsiThermo;
    mixture         pureMixture;
    transport       const;
    thermo          hConst;
    equationOfState perfectGas;
    specie          specie;
    energy          sensibleInternalEnergy;
}}
// rho = p/(R T) = {P_REF:g}/({r:.6g} * {t:.9g}) = {sc['rho_f']} kg/m3
mixture
{{
    specie {{ molWeight {MOL_WEIGHT}; }}
    thermodynamics {{ Cp 1005; Hf 0; }}
    transport {{ mu {g6(sc['mu'])}; Pr 0.7; }}
}}
"""
    scalar = lambda name, dim, v: foam.header("volScalarField", "0", name) + (
        f"dimensions      {dim};\ninternalField   uniform {v!r};\n"
        'boundaryField\n{\n    ".*" { type zeroGradient; }\n}\n')
    return th, scalar("p", "[1 -1 -2 0 0 0 0]", P_REF), scalar("T", "[0 0 0 1 0 0 0]", t)


def make_cases(sc, out):
    """One OpenFOAM case per particle density under `out`; returns the plan."""
    sc["boundary"] = boundary_types(sc["case"])
    for key in ("walls", "outlets", "inlets"):
        for p in sc[key]:
            if p not in sc["boundary"]:
                bad(sc["scene"], f"flow.patches.{key}", f"no patch {p!r} in the mesh ({sorted(sc['boundary'])})")
    for p in sc["interaction"]:
        if p not in sc["boundary"]:
            bad(sc["scene"], f"flow.patches.interaction.{p}", f"no patch {p!r} in the mesh ({sorted(sc['boundary'])})")
    # (a listed wall patch of another type than wall: localInteraction, which acts on any
    # patch; standardWallInteraction rebounds on wall patches only)
    for p, t in sc["boundary"].items():
        if t == "wall" and p not in sc["walls"]:
            bad(sc["scene"], "flow.patches.walls", f"wall patch {p!r} is not listed (scg would remove "
                "particles there, OpenFOAM rebound them)")
    for c in sc["classes"]:
        if c["patch"] not in sc["boundary"]:
            bad(sc["scene"], "feeders.patch", f"no patch {c['patch']!r} in the mesh")
    densities = sorted({c["density"] for c in sc["classes"]})
    runs = []
    for rho in densities:
        cls = [c for c in sc["classes"] if c["density"] == rho]
        d = os.path.join(out, f"rho{rho:g}")
        if os.path.exists(d):
            shutil.rmtree(d)
        os.makedirs(os.path.join(d, "constant", "polyMesh"))
        os.makedirs(os.path.join(d, "system"))
        os.makedirs(os.path.join(d, "0"))
        src = os.path.join(sc["case"], "constant", "polyMesh")
        for f in os.listdir(src):
            shutil.copy(os.path.join(src, f), os.path.join(d, "constant", "polyMesh", f))
        # the scene's field as the frozen U (OpenFOAM reads .gz files itself)
        shutil.copy(sc["field_file"], os.path.join(d, "0", "U" + (".gz" if sc["field_file"].endswith(".gz") else "")))
        for sub, name in (("system", "fvSchemes"), ("system", "fvSolution"),
                          ("constant", "turbulenceProperties")):
            shutil.copy(os.path.join(HERE, "..", "..", "bench", "openfoam", sub, name), os.path.join(d, sub, name))
        def w(rel, text):
            with open(os.path.join(d, rel), "w") as f:
                f.write(text)
        w("system/controlDict", control_dict(sc))
        w("constant/g", foam.header("uniformDimensionedVectorField", "constant", "g")
          + "dimensions      [0 1 -2 0 0 0 0];\nvalue           (%s);\n" % " ".join(g6(x) for x in sc["gravity"]))
        w("constant/transportProperties", foam.header("dictionary", "constant", "transportProperties")
          + f"transportModel  Newtonian;\nnu              {g6(sc['mu'] / sc['rho_f'])};\nrhoInf          {g6(sc['rho_f'])};\n")
        th, p, t = thermo(sc)
        w("constant/thermophysicalProperties", th)
        w("0/p", p)
        w("0/T", t)
        w("constant/kinematicCloudProperties", cloud_properties(sc, cls, rho))
        if sc.get("dispersion"):
            # the scene's turbulence fields, the same files scg reads, as the frozen k and
            # omega (epsilon), whatever their names (OpenFOAM reads a file by its name)
            dd = sc["dispersion"]
            for src, name in ((dd["k_file"], "k"), (dd["second_file"], dd["second"]), (dd.get("nut_file"), "nut")):
                if src:
                    shutil.copy(src, os.path.join(d, "0", name + (".gz" if src.endswith(".gz") else "")))
            for rel, text in turbulence_files(sc).items():
                w(rel, text)
        runs.append({"dir": d, "density": rho, "groups": [c["group"] for c in cls]})
    plan = {k: v for k, v in sc.items() if k != "boundary"}
    plan["patch_model"] = "standardWallInteraction" if standard_wall(sc) else "localInteraction"
    plan["patch_interactions"] = patch_interactions(sc)
    plan["fate_patches"] = fate_patches(sc)
    plan["runs"] = runs
    with open(os.path.join(out, "plan.json"), "w") as f:
        json.dump(plan, f, indent=1)
    return plan


# ---- reading OpenFOAM's results ------------------------------------------------------------

def internal_scalars(path):
    """The internalField of a volScalarField file (ascii or binary, .gz or not): a list of
    floats (a uniform field: one value)."""
    import struct
    op = gzip.open if path.endswith(".gz") else open
    with op(path, "rb") as f:
        raw = f.read()
    i = raw.index(b"internalField")
    m = re.compile(rb"internalField\s+uniform\s+([^;\s]+)\s*;").match(raw, i)
    if m:
        return [float(m.group(1))]
    m = re.compile(rb"internalField\s+nonuniform\s+List<scalar>\s*(\d+)\s*\(").match(raw, i)
    if not m:
        sys.exit(f"{path}: no scalar internalField")
    n = int(m.group(1))
    if re.search(rb"format\s+binary\s*;", raw[:i]):
        return list(struct.unpack(f"<{n}d", raw[m.end():m.end() + 8 * n]))
    vals = raw[m.end():raw.index(b")", m.end())].split()
    if len(vals) != n:
        sys.exit(f"{path}: {n} values announced, {len(vals)} read")
    return [float(x) for x in vals]


def frozen_check(d, names):
    """The largest relative difference between the input 0/NAME and the NAME the run wrote
    at its last time, per name (the turbulence model was not solved: 0)."""
    times = [x for x in os.listdir(d) if re.fullmatch(r"[0-9.eE+-]+", x) and float(x) > 0]
    out = {}
    for name in names:
        a = time_file(d, "0", name)
        b = time_file(d, max(times, key=float), name) if times else None
        if a is None or b is None:
            out[name] = None
            continue
        x, y = internal_scalars(a), internal_scalars(b)
        if len(x) != len(y):
            out[name] = None
            continue
        out[name] = max(abs(p - q) / max(abs(p), 1e-300) for p, q in zip(x, y))
    return out


def parse_log(log):
    """Per step (after each `Evolving` block): parcels in the system, ExecutionTime; the
    last `parcels added` per injector; the wall-clock of each ExecutionTime (LOG.wall)."""
    parcels, cpu, added, inj = [], [], {}, None
    fates, fate_patch = {}, None
    selected = {}
    with open(log) as f:
        for ln in f:
            # "Selecting dispersion model stochasticDispersionRAS",
            # "Selecting RAS turbulence model kOmegaSST"
            m = re.match(r"\s*Selecting (dispersion model|RAS turbulence model|turbulence model type)\s+(\S+)", ln)
            if m:
                selected[m.group(1)] = m.group(2)
            m = re.match(r"\s*betaStar\s+([0-9.eE+-]+)\s*;", ln)
            if m:
                selected["betaStar"] = float(m.group(1))
            # localInteraction's info, per patch (the totals so far; the last one counts):
            #     Parcel fate (number, mass)      : patch walls
            #       - escape                      = 0, 0
            #       - stick                       = 12, 1.2e-09
            m = re.match(r"\s*Parcel fate.*:\s*patch\s+(\S+)", ln)
            if m:
                fate_patch = m.group(1)
                fates[fate_patch] = {}
                continue
            m = re.match(r"\s*- (escape|stick|rebound)\s*=\s*(\d+)", ln)
            if m and fate_patch is not None:
                fates[fate_patch][m.group(1)] = int(m.group(2))
                continue
            if fate_patch is not None and not re.match(r"\s*-", ln):
                fate_patch = None
            m = re.match(r"\s*Current number of parcels\s*=\s*(\d+)", ln)
            if m:
                parcels.append(int(m.group(1)))
            m = re.match(r"ExecutionTime = ([0-9.eE+-]+) s", ln)
            if m:
                cpu.append(float(m.group(1)))
            m = re.match(r"\s*Injector (\S+):", ln)
            if m:
                inj = m.group(1)
            m = re.match(r"\s*- parcels added\s*=\s*(\d+)", ln)
            if m and inj is not None:
                added[inj] = int(m.group(1))
    wall = []
    if os.path.isfile(log + ".wall"):
        wall = [float(x) for x in read_text(log + ".wall").split()]
    return {"parcels": parcels, "cpu": cpu, "added": added, "wall": wall, "fates": fates,
            "selected": selected}


def timed_steps(case):
    """(particle-steps, wall seconds) of the run in `case` over steps 2..N: the parcels in
    the system after each step after the first, and LOG.wall's times of those steps."""
    lg = parse_log(os.path.join(case, "log.foam"))
    if len(lg["wall"]) < 2 or len(lg["wall"]) != len(lg["cpu"]):
        sys.exit(f"{case}/log.foam: {len(lg['cpu'])} ExecutionTime lines, {len(lg['wall'])} timed")
    return sum(lg["parcels"][1:]), lg["wall"][-1] - lg["wall"][0]


def diameters_at_end(case):
    """The diameters of the parcels written at the case's last time (> 0), or [] when
    none were written."""
    times = [x for x in os.listdir(case) if re.fullmatch(r"[0-9.eE+-]+", x) and float(x) > 0]
    if not times:
        return []
    dfile = os.path.join(case, max(times, key=float), "lagrangian", CLOUD, "d")
    return foam.foam_list(dfile, float) if os.path.isfile(dfile) else []


def foam_field(path, parse):
    """The entries of an ASCII OpenFOAM list file: `N ( ... )` one per line, on one line,
    or uniform `N{value}` (how v1912 writes a list whose entries are all equal)."""
    text = read_text(path)
    i = text.find("}", text.find("FoamFile")) + 1 if "FoamFile" in text else 0
    body = re.sub(r"//.*", "", text[i:])
    m = re.search(r"(\d+)\s*\{\s*([^}]*?)\s*\}", body)
    n = re.search(r"(\d+)\s*\(", body)
    if m and (n is None or m.start() < n.start()):
        return [parse(m.group(2))] * int(m.group(1))
    if n is None:
        return []
    inner = body[n.end():body.rindex(")")]
    count = int(n.group(1))
    items = [ln for ln in inner.splitlines() if ln.strip()]
    if len(items) != count:  # on one line: scalars separated by blanks
        items = inner.split()
    if len(items) != count:
        sys.exit(f"{path}: {count} entries announced, {len(items)} read")
    return [parse(x) for x in items]


def parcels_at_end(case):
    """(d, active) of the parcels written at the case's last time (> 0); active is False
    for a parcel stuck to a patch (localInteraction stick: kept inactive with U = 0)."""
    times = [x for x in os.listdir(case) if re.fullmatch(r"[0-9.eE+-]+", x) and float(x) > 0]
    if not times:
        return []
    d = os.path.join(case, max(times, key=float), "lagrangian", CLOUD)
    if not os.path.isfile(os.path.join(d, "d")):
        return []
    dia = foam_field(os.path.join(d, "d"), float)
    act = foam_field(os.path.join(d, "active"), lambda x: int(x) != 0) \
        if os.path.isfile(os.path.join(d, "active")) else [True] * len(dia)
    if len(act) != len(dia):
        sys.exit(f"{d}: {len(dia)} diameters against {len(act)} active flags")
    return list(zip(dia, act))


def write_json(dest, obj):
    with open(dest, "w") as f:
        json.dump(obj, f, indent=1)
        f.write("\n")


def read_post(case):
    """{patch: [(time, d, age), ...]} from patchPostProcessing's `<patch>.post` files (one
    folder per write time)."""
    root = os.path.join(case, "postProcessing", "lagrangian", CLOUD, PPP)
    hits = {}
    if not os.path.isdir(root):
        return hits
    for t in sorted(os.listdir(root), key=float):
        for fn in sorted(os.listdir(os.path.join(root, t))):
            if fn.endswith(".post"):
                with open(os.path.join(root, t, fn)) as f:
                    hits.setdefault(fn[:-5], []).extend(parse_post(f.read()))
    return hits


def parse_post(text):
    """(time, d, age) per parcel of a .post file. v1912 writes a header line
    `# Time currentProc (coordinates0 ... coordinates3) (position0 ...) celli ... d dTarget
    (U0 U1 U2) rho age ...` and one line per parcel with the same columns (vectors in
    parentheses): the columns are found by name."""
    cols, out = None, []
    for ln in text.splitlines():
        tok = ln.replace("(", " ").replace(")", " ").split()
        if ln.startswith("#"):
            cols = tok[1:]
            continue
        if not tok:
            continue
        if cols is None or len(tok) != len(cols):
            sys.exit(f"patchPostProcessing: a row of {len(tok)} columns against the header's {cols}")
        out.append((float(tok[cols.index("Time")]), float(tok[cols.index("d")]), float(tok[cols.index("age")])))
    return out


def nearest_class(d, classes):
    return min(classes, key=lambda c: abs(math.log(d / c["diameter"])))


def d50(classes):
    """Diameter where the efficiency crosses 0.5 (linear in log d between neighbours)."""
    pts = sorted((c["diameter"], c["efficiency"]) for c in classes if c["efficiency"] is not None)
    for (d0, e0), (d1, e1) in zip(pts, pts[1:]):
        if (e0 - 0.5) * (e1 - 0.5) <= 0 and e0 != e1:
            f = (0.5 - e0) / (e1 - e0)
            return math.exp(math.log(d0) + f * (math.log(d1) - math.log(d0)))
    return None


def grade(out, dest):
    plan = read_json(os.path.join(out, "plan.json"))
    classes = {c["group"]: dict(c, fed=0, escaped=0, held=0, lost=0, stuck=0, stuck_post=0, patches={},
                                residence_times=[])
               for c in plan["classes"]}
    ps = cpu = wall = 0.0
    notes = []
    inter = plan.get("patch_interactions", {})
    log_fates = {}
    disp = plan.get("dispersion")
    selected, frozen = {}, {}
    for run in plan["runs"]:
        d = run["dir"]
        lg = parse_log(os.path.join(d, "log.foam"))
        if not lg["cpu"]:
            sys.exit(f"{d}/log.foam: no step ran")
        selected[d] = lg["selected"]
        if disp:
            got = lg["selected"].get("dispersion model")
            if got != disp["foam_model"]:
                sys.exit(f"{d}/log.foam: dispersion model {got!r} selected, not {disp['foam_model']}")
            if lg["selected"].get("RAS turbulence model") != disp["ras_model"]:
                sys.exit(f"{d}/log.foam: RAS model {lg['selected'].get('RAS turbulence model')!r}, "
                         f"not {disp['ras_model']}")
            frozen[d] = frozen_check(d, ["k", disp["second"]])
            for name, diff in frozen[d].items():
                if diff is None:
                    notes.append(f"{d}: {name} not compared (not written at the end)")
                elif diff > 1e-15:
                    notes.append(f"{d}: {name} written at the end differs from the input by {diff:.3g} (relative)")
        for g in run["groups"]:
            if g not in lg["added"]:
                sys.exit(f"{d}/log.foam: no 'parcels added' for injector {g}")
            classes[g]["fed"] = lg["added"][g]
        cls = [classes[g] for g in run["groups"]]
        # timing: the steps after the first (start-up, mesh and field reading excluded)
        ps += sum(lg["parcels"][1:])
        cpu += lg["cpu"][-1] - lg["cpu"][0]
        if len(lg["wall"]) == len(lg["cpu"]):
            wall += lg["wall"][-1] - lg["wall"][0]
        post_counts = {}
        for patch, rows in read_post(d).items():
            model = inter.get(patch, {}).get("model", "escape")
            if model == "rebound":
                continue  # a bounce, not a fate
            post_counts[patch] = len(rows)
            for t, dia, age in rows:
                c = nearest_class(dia, cls)
                c["patches"][patch] = c["patches"].get(patch, 0) + 1
                if model == "stick":
                    c["stuck_post"] += 1
                elif patch in plan["outlets"]:
                    c["escaped"] += 1
                    c["residence_times"].append(age)
                else:
                    c["lost"] += 1
        written = parcels_at_end(d)
        for dia, active in written:
            nearest_class(dia, cls)["held" if active else "stuck"] += 1
        if len(lg["parcels"]) and lg["parcels"][-1] != len(written):
            notes.append(f"{d}: the log's last parcel count {lg['parcels'][-1]} differs from the parcels "
                         f"written ({len(written)})")
        for c in cls:
            if c["stuck"] != c["stuck_post"]:
                notes.append(f"{c['group']}: {c['stuck']} parcels written inactive (stuck) at the end, "
                             f"{c['stuck_post']} recorded by patchPostProcessing on stick patches")
        # localInteraction's per-patch totals in the log against patchPostProcessing
        for patch, f in lg["fates"].items():
            n = sum(f.values())
            log_fates.setdefault(patch, {})
            for k, v in f.items():
                log_fates[patch][k] = log_fates[patch].get(k, 0) + v
            if patch in post_counts and post_counts[patch] != n:
                notes.append(f"{d}: patch {patch}: the log's parcel fate counts {f} against "
                             f"{post_counts[patch]} parcels in patchPostProcessing")
    out_classes = []
    for c in plan["classes"]:
        k = classes[c["group"]]
        fed = k["fed"]
        gone = fed - k["escaped"] - k["held"] - k["lost"] - k["stuck"]
        if gone:
            notes.append(f"{c['group']}: {gone} parcels neither escaped, held, stuck nor lost "
                         "(removed by OpenFOAM otherwise)")
        out_classes.append({
            "group": c["group"], "diameter": c["diameter"], "density": c["density"],
            "fed": fed, "escaped": k["escaped"], "held": k["held"], "lost": k["lost"],
            "stuck": k["stuck"], "patches": k["patches"],
            "efficiency": (1.0 - k["escaped"] / fed) if fed else None,
            "residence_times": k["residence_times"],
        })
    if len(plan["runs"]) > 1:
        notes.append(f"{len(plan['runs'])} OpenFOAM runs, one per particle density (one cloud has one rho0); "
                     "particle-steps and times summed")
    notes += [
        "uncoupledKinematicParcelFoam, 1 process; frozen U = the scene's "
        f"{plan['field']} at time {plan['time']}; U interpolation {plan['foam_interpolation']}",
        ("dispersion: none" if not disp else
         f"dispersion: {disp['foam_model']} (scene {disp['model']}); frozen RAS {disp['ras_model']}: "
         f"k = the scene's {disp['k']}, {disp['second']} = its {disp['second_name']}"
         + (" (epsilon = betaStar k omega)" if disp["second"] == "omega" else "")
         + "; cell values of the parcel's cell; not solved (k and " + disp["second"]
         + " written at the end = the inputs: frozen_check, max relative difference)"),
        "drag: sphereDrag, Cd Re/24 = 1 + Re^(2/3)/6 (scg: " + plan["drag"] + ")",
        (f"walls: standardWallInteraction rebound e = {plan['restitution']}, mu = 0"
         if plan.get("patch_model", "standardWallInteraction") == "standardWallInteraction" else
         "patches: localInteraction " + ", ".join(
             f"{p} {i['model']}" + (f" (e {i['e']}, mu {i['mu']})" if i["model"] == "rebound" else "")
             for p, i in sorted(inter.items()))),
        "escaped: parcels reaching the outlet patch(es) " + ", ".join(plan["outlets"])
        + "; lost: other escape patches; stuck: parcels written inactive at the end (stick patches); "
        "held: active parcels written at the end; residence time = parcel age at the patch",
        "particle_steps: sum over steps 2..N of 'Current number of parcels'; cpu_s: ExecutionTime "
        "(process CPU) of the same steps; wall_s: wall time of the same log lines",
    ]
    g = {
        "code": "openfoam", "version": "v1912", "classes": out_classes, "d50": d50(out_classes),
        "particle_steps": int(ps), "cpu_s": cpu, "wall_s": wall,
        "particle_steps_per_s": ps / cpu if cpu > 0 else None, "dt": plan["dt"],
        "patch_model": plan.get("patch_model", "standardWallInteraction"), "log_fates": log_fates,
        "dispersion": disp["foam_model"] if disp else "none",
        "turbulence": ({"model": disp["ras_model"], "k": disp["k"], disp["second"]: disp["second_name"]}
                       if disp else None),
        "selected": selected, "frozen_check": frozen,
        "notes": notes,
    }
    write_json(dest, g)
    return g


def parallel(dest, dirs, decomposition):
    """The speed of the decomposed runs in `dirs` (mpirun -np N ... -parallel): their
    particle-steps and wall time over steps 2..N (as `grade`), and the parcels each
    processor held at the end (from processor*/<last time>/lagrangian). Exits with an
    error when a processor held none of at least 10 per processor: one core would have
    idled."""
    ps = wall = 0.0
    ranks, per_rank = 0, []
    for d in dirs:
        steps, secs = timed_steps(d)
        ps += steps
        wall += secs
        procs = sorted((x for x in os.listdir(d) if re.fullmatch(r"processor\d+", x)),
                       key=lambda x: int(x[9:]))
        if not procs:
            sys.exit(f"{d}: no processor folders (not a decomposed case)")
        ranks = max(ranks, len(procs))
        held = [len(diameters_at_end(os.path.join(d, pr))) for pr in procs]
        # (a domain nearly empty at the end says nothing of the balance during the run)
        if min(held) == 0 and sum(held) >= 10 * len(held):
            sys.exit(f"{d}: a processor held no parcel at the end ({held}): one core idled")
        per_rank.append(held)
    out = {
        "code": "openfoam", "ranks": ranks, "decomposition": decomposition,
        "particle_steps": int(ps), "wall_s": wall,
        "particle_steps_per_s": ps / wall if wall > 0 else None,
        "parcels_per_rank_at_end": per_rank,
    }
    write_json(dest, out)
    return out


def concurrent(dest, dirs):
    """The machine's throughput of serial runs started together, one per core (`dirs`, each
    a copy of the same case): the sum over the runs of their particle-steps per wall second
    over steps 2..N. Another way for OpenFOAM to use several cores, an upper bound when the
    runs are independent cases."""
    rates, per = 0.0, []
    for d in dirs:
        ps, wall = timed_steps(d)
        per.append({"dir": d, "particle_steps": ps, "wall_s": wall})
        rates += ps / wall
    out = {"code": "openfoam", "processes": len(dirs), "runs": per, "particle_steps_per_s": rates}
    write_json(dest, out)
    return out


def efficiency(fed, escaped):
    return 1.0 - escaped / fed if fed else None


def sampling_pp(fed1, e1, fed2, e2):
    """One standard deviation of the difference of two independent binomial escape
    fractions, percentage points (each class's particles escape or not independently)."""
    if not fed1 or not fed2 or e1 is None or e2 is None:
        return None
    return 100.0 * math.sqrt(e1 * (1 - e1) / fed1 + e2 * (1 - e2) / fed2)


def rows(fo, s1):
    """Per class: (group, d, OpenFOAM class, scg group, efficiency OpenFOAM, scg,
    difference scg - OpenFOAM in pp, its sampling sigma in pp)."""
    by = {g["group"]: g for g in s1["groups"]}
    out = []
    for c in fo["classes"]:
        s = by[c["group"]]
        ef, es = c["efficiency"], efficiency(s["fed"], s["drained"])
        diff = (es - ef) * 100.0 if es is not None and ef is not None else None
        out.append((c["group"], c["diameter"], c, s, ef, es, diff, sampling_pp(c["fed"], ef, s["fed"], es)))
    return out


def table(grade_path, scg1_path, scg2_path, parallel_path=None, concurrent_path=None):
    fo, s1, s2 = read_json(grade_path), read_json(scg1_path), read_json(scg2_path)
    fp = read_json(parallel_path) if parallel_path else None
    fc = read_json(concurrent_path) if concurrent_path else None
    print(f"{'class':>6} {'d [µm]':>7} | {'OpenFOAM':>8} {'fed':>5} {'esc':>5} {'held':>5} {'lost':>4} "
          f"| {'scg':>8} {'fed':>5} {'esc':>5} {'held':>5} {'lost':>4} | {'diff [pp]':>9} {'sigma':>6}")
    fmt = lambda e: f"{e:8.4f}" if e is not None else f"{'-':>8}"
    fpp = lambda x, w: f"{x:+{w}.2f}" if x is not None else f"{'-':>{w}}"
    worst = None
    for g, d, c, s, ef, es, diff, sig in rows(fo, s1):
        if diff is not None and (worst is None or abs(diff) > worst):
            worst = abs(diff)
        print(f"{g:>6} {d * 1e6:7.3g} | {fmt(ef)} {c['fed']:5d} {c['escaped']:5d} {c['held']:5d} {c['lost']:4d} "
              f"| {fmt(es)} {s['fed']:5d} {s['drained']:5d} {s['held']:5d} {s['lost']:4d} "
              f"| {fpp(diff, 9)} {(f'{sig:6.2f}' if sig is not None else '-'):>6}")
    print("  (efficiency = 1 - escaped/fed; diff = scg - OpenFOAM; sigma: one standard deviation "
          "of the difference from sampling alone, binomial)")
    scg_d50 = d50([{"diameter": g["diameter"], "efficiency": efficiency(g["fed"], g["drained"])}
                   for g in s1["groups"]])
    um = lambda x: f"{x * 1e6:.2f} µm" if x is not None else "none (the efficiency does not cross 0.5)"
    print(f"d50: OpenFOAM {um(fo['d50'])}, scg {um(scg_d50)}")
    if fo.get("dispersion", "none") != "none":
        t = fo.get("turbulence") or {}
        print(f"OpenFOAM dispersion: {fo['dispersion']} on frozen RAS {t.get('model')} ("
              + ", ".join(f"{k} = {v}" for k, v in t.items() if k != "model") + ")")
    for name, res in (("OpenFOAM", [c["residence_times"] for c in fo["classes"]]),):
        med = [f"{c['group']} {sorted(r)[len(r) // 2]:.3g} s" for c, r in zip(fo["classes"], res) if r]
        print(f"median residence time of the escaped ({name}): " + (", ".join(med) or "-"))
    print("speed, particle-steps/s (particle-steps = sum over steps of the particles in the domain):")
    print(f"  OpenFOAM, 1 process: {fo['particle_steps_per_s']:.4e}  ({fo['particle_steps']} in {fo['cpu_s']:.2f} s "
          f"CPU: ExecutionTime of steps 2..N; wall {fo['wall_s']:.2f} s)")
    for s in (s1, s2):
        print(f"  scg, {s['threads']} thread{'s' if s['threads'] > 1 else ' '}:       {s['particle_steps_per_s']:.4e}  "
              f"({s['particle_steps']} in {s['wall_s']:.2f} s wall: the run's steps)")
    if fp is not None:
        held = " / ".join(str(n) for n in fp["parcels_per_rank_at_end"][0])
        print(f"  OpenFOAM, {fp['ranks']} ranks:   {fp['particle_steps_per_s']:.4e}  ({fp['particle_steps']} in "
              f"{fp['wall_s']:.2f} s wall, steps 2..N; {fp['decomposition']}; parcels per rank at the end {held})")
    if fc is not None:
        walls = ", ".join(f"{r['wall_s']:.2f}" for r in fc["runs"])
        print(f"  OpenFOAM, {fc['processes']} serial runs at once: {fc['particle_steps_per_s']:.4e}  (sum of their "
              f"rates; {walls} s wall)")
    print(f"max efficiency difference: {worst:.2f} pp" if worst is not None else "max efficiency difference: -")
    print(f"speed ratio per core (scg 1 thread / OpenFOAM 1 process, CPU): "
          f"{s1['particle_steps_per_s'] / fo['particle_steps_per_s']:.2f}")
    both = [(x["particle_steps_per_s"], name) for x, name in
            ((fp, "its decomposed run"), (fc, "serial runs at once")) if x is not None]
    if both:
        best, how = max(both)
        print(f"speed ratio, the machine's 2 cores (scg 2 threads / OpenFOAM's faster use of them, {how}): "
              f"{s2['particle_steps_per_s'] / best:.2f}")
    else:
        print(f"speed ratio (scg 2 threads / OpenFOAM 1 process): "
              f"{s2['particle_steps_per_s'] / fo['particle_steps_per_s']:.2f}")


def summary(grade_path, parallel_path=None, concurrent_path=None):
    """OpenFOAM's side alone (vs-openfoam.sh --openfoam-only)."""
    fo = read_json(grade_path)
    print(f"OpenFOAM v1912, dispersion {fo.get('dispersion', 'none')}"
          + (f" (RAS {fo['turbulence']['model']}: " + ", ".join(f"{k} = {v}" for k, v in fo["turbulence"].items()
                                                            if k != "model") + ")" if fo.get("turbulence") else ""))
    print(f"{'class':>6} {'d [µm]':>7} | {'efficiency':>10} {'fed':>5} {'esc':>5} {'held':>5} {'lost':>4} {'stuck':>5}")
    for c in fo["classes"]:
        e = c["efficiency"]
        print(f"{c['group']:>6} {c['diameter'] * 1e6:7.3g} | {(f'{e:10.4f}' if e is not None else '-'):>10} "
              f"{c['fed']:5d} {c['escaped']:5d} {c['held']:5d} {c['lost']:4d} {c['stuck']:5d}")
    um = lambda x: f"{x * 1e6:.2f} µm" if x is not None else "none (the efficiency does not cross 0.5)"
    print(f"d50: {um(fo['d50'])}")
    print(f"speed: 1 process {fo['particle_steps_per_s']:.4e} particle-steps/s ({fo['particle_steps']} in "
          f"{fo['cpu_s']:.2f} s CPU, {fo['wall_s']:.2f} s wall, steps 2..N)")
    if parallel_path:
        fp = read_json(parallel_path)
        print(f"       {fp['ranks']} ranks {fp['particle_steps_per_s']:.4e} ({fp['wall_s']:.2f} s wall)")
    if concurrent_path:
        fc = read_json(concurrent_path)
        print(f"       {fc['processes']} serial runs at once {fc['particle_steps_per_s']:.4e} (summed)")
    for d, f in (fo.get("frozen_check") or {}).items():
        print(f"frozen turbulence ({os.path.basename(d)}): max relative difference input/end "
              + ", ".join(f"{k} {v:.3g}" if v is not None else f"{k} -" for k, v in f.items()))


def main(argv):
    import argparse
    ap = argparse.ArgumentParser(prog="vs_openfoam.py")
    sub = ap.add_subparsers(dest="cmd", required=True)
    c = sub.add_parser("case")
    c.add_argument("scene")
    c.add_argument("dir")
    c.add_argument("--duration", type=float)
    c.add_argument("--feed-scale", type=float)
    c.add_argument("--dt", type=float)
    lk = sub.add_parser("like")
    lk.add_argument("scene")
    lk.add_argument("out")
    g = sub.add_parser("grade")
    g.add_argument("dir")
    g.add_argument("out")
    t = sub.add_parser("table")
    t.add_argument("grade")
    t.add_argument("scg1")
    t.add_argument("scg2")
    t.add_argument("parallel", nargs="?")
    t.add_argument("concurrent", nargs="?")
    m = sub.add_parser("summary")
    m.add_argument("grade")
    m.add_argument("parallel", nargs="?")
    m.add_argument("concurrent", nargs="?")
    q = sub.add_parser("concurrent")
    q.add_argument("out")
    q.add_argument("dirs", nargs="+")
    p = sub.add_parser("parallel")
    p.add_argument("out")
    p.add_argument("decomposition")
    p.add_argument("dirs", nargs="+")
    a = ap.parse_args(argv[1:])
    try:
        if a.cmd == "case":
            plan = make_cases(read_scene(a.scene, a.duration, a.feed_scale, a.dt), a.dir)
            for r in plan["runs"]:
                print(r["dir"])
        elif a.cmd == "like":
            for c in like(a.scene, a.out):
                print(c)
        elif a.cmd == "grade":
            grade(a.dir, a.out)
        elif a.cmd == "parallel":
            parallel(a.out, a.dirs, a.decomposition)
        elif a.cmd == "concurrent":
            concurrent(a.out, a.dirs)
        elif a.cmd == "summary":
            summary(a.grade, a.parallel, a.concurrent)
        else:
            table(a.grade, a.scg1, a.scg2, a.parallel, a.concurrent)
    except SceneError as e:
        print(f"error: {e}", file=sys.stderr)
        sys.exit(2)


if __name__ == "__main__":
    main(sys.argv)
