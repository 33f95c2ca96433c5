"""SSP 1.0 system of the turbocharger: one rotor FMU, two bearing FMUs, their connections and parameter sets.

:func:`write_ssp` generates ``ssp/`` (SystemStructure.ssd + one .ssv per parameter set and component);
:func:`read_ssp` parses a folder or ``.ssp`` archive for the master. The SSD is flat (no system-level
connectors) and carries the OSP fixed-step annotation, so libcosim runs it unchanged.
"""
from __future__ import annotations

import math
import tempfile
import zipfile
from dataclasses import dataclass, field
from pathlib import Path
from xml.etree import ElementTree as ET


NS = {"ssd": "http://ssp-standard.org/SSP1/SystemStructureDescription",
      "ssc": "http://ssp-standard.org/SSP1/SystemStructureCommon",
      "ssv": "http://ssp-standard.org/SSP1/SystemStructureParameterValues",
      "osp": "http://opensimulationplatform.com/SSP/OSPAnnotations"}
BEARINGS = (("turbine", "turbine_bearing"), ("compressor", "compressor_bearing"))
DEFAULT_SET = "co36"


def _bearing_connections(inst, prefix):
    con = [("rotor", f"{prefix}.journal.{q}", inst, f"journal.{q}") for q in ("x", "y", "vx", "vy")]
    con.append(("rotor", "rotor_speed", inst, "rotor_speed"))
    con += [(inst, f"force.{q}", "rotor", f"{prefix}.force.{q}") for q in "xy"]
    con += [(inst, f"journal_ref.{q}", "rotor", f"{prefix}.journal_ref.{q}") for q in ("x", "y", "vx", "vy")]
    con += [(inst, f"force_end.{q}", "rotor", f"{prefix}.force_end.{q}") for q in "xy"]
    con += [(inst, f"journal_accel.{q}", "rotor", f"{prefix}.journal_accel.{q}") for q in "xy"]
    for m in ("stiffness", "damping"):
        con += [(inst, f"{m}[{i},{k}]", "rotor", f"{prefix}.{m}[{i},{k}]") for i in (1, 2) for k in (1, 2)]
    return con


def connections():
    """(start element, start connector, end element, end connector) of the system."""
    out = []
    for inst, prefix in BEARINGS:
        out += _bearing_connections(inst, prefix)
    return out


def _unit(conn):
    """Unit of a connector, from its name."""
    if "journal_accel." in conn:
        return "m/s2"
    if "journal.v" in conn or "journal_ref.v" in conn:
        return "m/s"
    if "journal." in conn or "journal_ref." in conn:
        return "m"
    if "rotor_speed" in conn:
        return "rad/s"
    if "force." in conn or "force_end." in conn:
        return "N"
    if "stiffness" in conn:
        return "N/m"
    if "damping" in conn:
        return "N.s/m"
    raise ValueError(f"no unit known for connector {conn!r}")


UNITS = {"m": dict(m=1), "m/s": dict(m=1, s=-1), "m/s2": dict(m=1, s=-2), "rad/s": dict(rad=1, s=-1), "N": dict(kg=1, m=1, s=-2),
         "N/m": dict(kg=1, s=-2), "N.s/m": dict(kg=1, s=-1)}


def parameter_sets(clearances=(36e-6, 40e-6, 42e-6, 46e-6), start_rpm=20e3, end_rpm=250e3, ramp_time=1.0,
                   perturbation=0.05):
    """{set name: {component: {parameter: (type, value, unit)}}} with initial states from the method-J
    equilibrium at the start speed (journals and rings offset in +x by ``perturbation`` × clearance, as in
    :func:`frbmodel.runup.runup`)."""
    import frbmodel as frb

    sets = {}
    for c in clearances:
        tc = frb.turbocharger(outer_clearance=c)
        eq = frb.equilibrium(tc, "J", start_rpm)
        name = f"co{c * 1e6:.0f}"
        comp = {"rotor": {"speed_start": ("Real", start_rpm * math.pi / 30, "rad/s"),
                          "speed_end": ("Real", end_rpm * math.pi / 30, "rad/s"),
                          "ramp_time": ("Real", ramp_time, "s"), "gravity": ("Real", tc.gravity, "m/s2")}}
        from ..components import BearingComponent

        w0 = start_rpm * math.pi / 30
        for (inst, prefix), b, e in zip(BEARINGS, tc.bearings, eq.bearings):
            jx = float(e.journal[0] + perturbation * (b.inner.clearance + b.outer.clearance))
            rx = float(e.ring[0] + perturbation * b.outer.clearance)
            comp["rotor"][f"{prefix}.journal_x0"] = ("Real", jx, "m")
            comp["rotor"][f"{prefix}.journal_y0"] = ("Real", float(e.journal[1]), "m")
            # start values of the coupling inputs consistent with the initial state, so that a master that
            # steps before its first exchange (e.g. libcosim) starts from the same point
            bc = BearingComponent(b, tc.film_model)
            bc.ring[:] = [rx, e.ring[1], 0.0, 0.0, e.ring_speed]
            F, K, C, _ = bc.outputs([jx, e.journal[1], 0.0, 0.0], w0)
            for q, val in zip(("x", "y", "vx", "vy"), (jx, float(e.journal[1]), 0.0, 0.0)):
                comp["rotor"][f"{prefix}.journal_ref.{q}"] = ("Real", val, "m" if len(q) == 1 else "m/s")
            comp["rotor"][f"{prefix}.force_end.x"] = ("Real", float(F[0]), "N")
            comp["rotor"][f"{prefix}.force_end.y"] = ("Real", float(F[1]), "N")
            comp["rotor"][f"{prefix}.force.x"] = ("Real", float(F[0]), "N")
            comp["rotor"][f"{prefix}.force.y"] = ("Real", float(F[1]), "N")
            for i in range(2):
                for k in range(2):
                    comp["rotor"][f"{prefix}.stiffness[{i + 1},{k + 1}]"] = ("Real", float(K[i, k]), "N/m")
                    comp["rotor"][f"{prefix}.damping[{i + 1},{k + 1}]"] = ("Real", float(C[i, k]), "N.s/m")
            p = {"journal.x": ("Real", jx, "m"), "journal.y": ("Real", float(e.journal[1]), "m"),
                 "rotor_speed": ("Real", w0, "rad/s")}
            for fname, film in (("inner", b.inner), ("outer", b.outer)):
                p[f"{fname}.radius"] = ("Real", film.radius, "m")
                p[f"{fname}.length"] = ("Real", film.length, "m")
                p[f"{fname}.clearance"] = ("Real", film.clearance, "m")
                p[f"{fname}.viscosity"] = ("Real", film.viscosity, "Pa.s")
            p["ring.mass"] = ("Real", b.ring_mass, "kg")
            p["ring.inertia"] = ("Real", b.ring_inertia, "kg.m2")
            p["ring.x0"] = ("Real", rx, "m")
            p["ring.y0"] = ("Real", float(e.ring[1]), "m")
            p["ring.speed0"] = ("Real", float(e.ring_speed), "rad/s")
            p["gravity"] = ("Real", tc.gravity, "m/s2")
            p["film_model"] = ("String", tc.film_model, None)
            p["ring_speed_model"] = ("String", "free", None)
            comp[inst] = p
        sets[name] = comp
    return sets


def write_ssp(out_dir="ssp", step_size=1e-5, stop_time=1.0, **kw):
    """Write ``SystemStructure.ssd`` and ``resources/<set>_<component>.ssv`` into ``out_dir``."""
    out = Path(out_dir)
    (out / "resources").mkdir(parents=True, exist_ok=True)
    for k, v in NS.items():
        ET.register_namespace(k, v)
    q = lambda ns, tag: f"{{{NS[ns]}}}{tag}"  # noqa: E731
    root = ET.Element(q("ssd", "SystemStructureDescription"), {"version": "1.0", "name": "turbocharger"})
    system = ET.SubElement(root, q("ssd", "System"), {"name": "turbocharger", "description":
                           "Turbocharger rotor on two floating-ring bearings (frbmodel), interface-Jacobian coupling"})
    elements = ET.SubElement(system, q("ssd", "Elements"))
    cons = connections()
    comps = [("rotor", "TurbochargerRotor")] + [(inst, "FloatingRingBearing") for inst, _ in BEARINGS]
    for name, fmu in comps:
        el = ET.SubElement(elements, q("ssd", "Component"), {"name": name, "source": f"resources/{fmu}.fmu",
                                                              "type": "application/x-fmu-sharedlibrary"})
        ctors = ET.SubElement(el, q("ssd", "Connectors"))
        for s_el, s_c, e_el, e_c in cons:
            for el_name, c_name, kind in ((s_el, s_c, "output"), (e_el, e_c, "input")):
                if el_name == name:
                    ce = ET.SubElement(ctors, q("ssd", "Connector"), {"name": c_name, "kind": kind})
                    ET.SubElement(ce, q("ssc", "Real"), {"unit": _unit(c_name)})
        pb = ET.SubElement(el, q("ssd", "ParameterBindings"))
        ET.SubElement(pb, q("ssd", "ParameterBinding"), {"source": f"resources/{DEFAULT_SET}_{name}.ssv"})
    cs = ET.SubElement(system, q("ssd", "Connections"))
    for s_el, s_c, e_el, e_c in cons:
        ET.SubElement(cs, q("ssd", "Connection"), {"startElement": s_el, "startConnector": s_c,
                                                   "endElement": e_el, "endConnector": e_c})
    units = ET.SubElement(root, q("ssd", "Units"))
    for uname, base in UNITS.items():
        u = ET.SubElement(units, q("ssc", "Unit"), {"name": uname})
        ET.SubElement(u, q("ssc", "BaseUnit"), {k: str(v) for k, v in base.items()})
    de = ET.SubElement(root, q("ssd", "DefaultExperiment"), {"startTime": "0", "stopTime": repr(float(stop_time))})
    ann = ET.SubElement(ET.SubElement(de, q("ssd", "Annotations")), q("ssc", "Annotation"),
                        {"type": "com.opensimulationplatform"})
    alg = ET.SubElement(ann, q("osp", "Algorithm"))
    ET.SubElement(alg, q("osp", "FixedStepAlgorithm"), {"baseStepSize": repr(float(step_size))})
    ET.indent(root)
    paths = [out / "SystemStructure.ssd"]
    ET.ElementTree(root).write(paths[0], xml_declaration=True, encoding="UTF-8")
    for set_name, comps_p in parameter_sets(**kw).items():
        for comp, params in comps_p.items():
            ps = ET.Element(q("ssv", "ParameterSet"), {"version": "1.0", "name": set_name})
            pars = ET.SubElement(ps, q("ssv", "Parameters"))
            for pname, (typ, val, unit) in params.items():
                p = ET.SubElement(pars, q("ssv", "Parameter"), {"name": pname})
                attrs = {"value": repr(float(val)) if typ == "Real" else str(val)}
                ET.SubElement(p, q("ssv", typ), attrs)
            ET.indent(ps)
            f = out / "resources" / f"{set_name}_{comp}.ssv"
            ET.ElementTree(ps).write(f, xml_declaration=True, encoding="UTF-8")
            paths.append(f)
    return paths


@dataclass
class SSPSystem:
    """Parsed system: components {name: fmu path}, connections, parameter sets, step and stop time."""

    root: Path
    components: dict
    connections: list
    parameter_files: dict = field(default_factory=dict)  # set name -> {component: path}
    step_size: float | None = None
    stop_time: float | None = None

    def parameters(self, set_name):
        """{component: {name: (type, value)}} of parameter set ``set_name``."""
        if set_name not in self.parameter_files:
            from ..errors import ParameterError

            raise ParameterError(f"parameter set = {set_name!r} is unknown; available: {sorted(self.parameter_files)}")
        return {c: read_ssv(p) for c, p in self.parameter_files[set_name].items()}


def read_ssv(path):
    tree = ET.parse(path)
    out = {}
    for p in tree.getroot().iter(f"{{{NS['ssv']}}}Parameter"):
        for child in p:
            typ = child.tag.split("}")[1]
            v = child.get("value")
            out[p.get("name")] = (typ, float(v) if typ == "Real" else int(v) if typ == "Integer" else
                                  (v.lower() == "true") if typ == "Boolean" else v)
    return out


def read_ssp(path) -> SSPSystem:
    """Parse an SSP folder or archive (an archive is extracted to a temporary folder)."""
    from ..errors import ParameterError

    path = Path(path)
    if not path.exists():
        raise ParameterError(f"SSP = {str(path)!r} does not exist")
    if path.is_file():
        tmp = Path(tempfile.mkdtemp(prefix="frb_ssp_"))
        try:
            with zipfile.ZipFile(path) as z:
                z.extractall(tmp)
        except zipfile.BadZipFile:
            raise ParameterError(f"SSP = {str(path)!r} is not a valid .ssp (zip) archive") from None
        path = tmp
    ssd = path / "SystemStructure.ssd"
    if not ssd.exists():
        raise ParameterError(f"SSP {str(path)!r} has no SystemStructure.ssd")
    try:
        root = ET.parse(ssd).getroot()
    except ET.ParseError as exc:
        raise ParameterError(f"SystemStructure.ssd is not well-formed XML: {exc}") from None
    comps = {}
    for c in root.iter(f"{{{NS['ssd']}}}Component"):
        comps[c.get("name")] = path / c.get("source")
    cons = [(c.get("startElement"), c.get("startConnector"), c.get("endElement"), c.get("endConnector"))
            for c in root.iter(f"{{{NS['ssd']}}}Connection")]
    for s_el, s_c, e_el, e_c in cons:
        for el in (s_el, e_el):
            if el not in comps:
                raise ParameterError(f"SSP connection {s_el}.{s_c} -> {e_el}.{e_c} names an unknown component "
                                     f"{el!r}; components are {sorted(comps)}")
    sets = {}
    for f in sorted((path / "resources").glob("*_*.ssv")):
        set_name, comp = f.stem.split("_", 1)
        sets.setdefault(set_name, {})[comp] = f
    step = stop = None
    fsa = root.find(".//osp:FixedStepAlgorithm", NS)
    if fsa is not None:
        step = float(fsa.get("baseStepSize"))
    de = root.find("ssd:DefaultExperiment", NS)
    if de is not None and de.get("stopTime"):
        stop = float(de.get("stopTime"))
    return SSPSystem(path, comps, cons, sets, step, stop)


__all__ = ["write_ssp", "read_ssp", "read_ssv", "connections", "parameter_sets", "SSPSystem"]
