"""SSP 1.0 systems: the turbocharger split into one rotor FMU and two bearing FMUs (their connections and parameter
sets, :func:`write_ssp`), and the example engine side driving the whole-turbocharger FMU (:func:`write_engine_ssp`).

The system is the rotor FMU's (default: the paper's Table 2 turbocharger): the bearing components are named after
its bearings, and connect to the rotor's ``<bearing>_bearing.*`` variables.

:func:`write_ssp` generates ``ssp/``; :func:`read_ssp` parses a folder or ``.ssp`` archive for the master.
The SSD is flat (no system-level connectors) and carries the OSP fixed-step annotation, so libcosim runs it
unchanged.

Parameter sets are SSP *variants*: the archive's default ``SystemStructure.ssd`` binds the first set (co36)
and one more SSD per further set (``co40.ssd``, ...: the same system) binds that set, each component through
its ``ssd:ParameterBindings`` to a ``resources/<set>_<component>.ssv``. SSP 1.0 applies *all* bindings of a
component (later ones override earlier ones), so alternative sets cannot be listed side by side in one SSD;
variants are the standard's way (an SSP may hold several .ssd files at its root, SystemStructure.ssd being the
default one), any SSP tool runs the default, and libcosim can load a variant by its SSD file name. The reader
takes every binding from the SSDs (file names carry no meaning) and names a set by the ``name`` of the
``ssv:ParameterSet`` its SSD binds.

An ``.ssp`` archive is extracted to a temporary folder owned by the :class:`SSPSystem` that :func:`read_ssp`
returns: :meth:`SSPSystem.close` (or leaving its ``with`` block) deletes it, and so does garbage collection of
the object or the end of the interpreter, whichever comes first.
"""
from __future__ import annotations

import shutil
import tempfile
import weakref
import zipfile
from dataclasses import dataclass, field
from pathlib import Path
from xml.etree import ElementTree as ET

from ..core.errors import ParameterError
from ..core.units import rpm_to_rad_s
from ..linear.equilibrium import equilibrium
from ..nonlinear.components import BearingComponent
from ..system.presets import DEFAULT_OUTER_CLEARANCE_M, PAPER_OUTER_CLEARANCES, turbocharger

NS = {"ssd": "http://ssp-standard.org/SSP1/SystemStructureDescription",
      "ssc": "http://ssp-standard.org/SSP1/SystemStructureCommon",
      "ssv": "http://ssp-standard.org/SSP1/SystemStructureParameterValues",
      "osp": "http://opensimulationplatform.com/SSP/OSPAnnotations"}
#: the default variant of an SSP (SSP 1.0); further variants are the other .ssd files at the archive's root
DEFAULT_SSD = "SystemStructure.ssd"
PARAMETER_SET_TYPE = "application/x-ssp-parameter-set"


def _bearing_connections(inst, prefix):
    con = [("rotor", f"{prefix}.journal.{q}", inst, f"journal.{q}") for q in ("x", "y", "vx", "vy")]
    con.append(("rotor", "rotor_speed", inst, "rotor_speed"))
    con += [(inst, f"force.{q}", "rotor", f"{prefix}.force.{q}") for q in "xy"]
    con += [(inst, f"journal_ref.{q}", "rotor", f"{prefix}.journal_ref.{q}") for q in ("x", "y", "vx", "vy")]
    con.append((inst, "journal_torque", "rotor", f"{prefix}.torque"))
    con += [(inst, f"force_end.{q}", "rotor", f"{prefix}.force_end.{q}") for q in "xy"]
    con += [(inst, f"journal_accel.{q}", "rotor", f"{prefix}.journal_accel.{q}") for q in "xy"]
    for m in ("stiffness", "damping"):
        con += [(inst, f"{m}.{i}{k}", "rotor", f"{prefix}.{m}.{i}{k}") for i in "xy" for k in "xy"]
    return con


def _table2(system):
    """``system``, or the paper's Table 2 turbocharger when it is None."""
    if system is not None:
        return system

    return turbocharger()


def bearing_components(system=None):
    """``(component name, rotor variable prefix)`` per bearing of ``system``: ``(name, "<name>_bearing")``.

    Parameters
    ----------
    system : Turbocharger, optional
        The system the rotor FMU is built for (default: the paper's Table 2 turbocharger).

    Returns
    -------
    list of tuple
    """
    return [(b.name, f"{b.name}_bearing") for b in _table2(system).bearings]


def connections(system=None):
    """Connections of the system (per bearing: rotor -> bearing journal state and speed, bearing -> rotor force,
    reference journal state, film torque on the journal, end-of-step values and interface Jacobian).

    Parameters
    ----------
    system : Turbocharger, optional
        The system the rotor FMU is built for (default: the paper's Table 2 turbocharger); its bearing names
        name the bearing components.

    Returns
    -------
    list of tuple
        ``(start element, start connector, end element, end connector)``.
    """
    out = []
    for inst, prefix in bearing_components(system):
        out += _bearing_connections(inst, prefix)
    return out


def _unit(conn):
    """Unit of a connector, from its name."""
    if conn.endswith("torque"):
        return "N.m"
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


UNITS = {"m": dict(m=1), "m/s": dict(m=1, s=-1), "m/s2": dict(m=1, s=-2), "rad/s": dict(rad=1, s=-1),
         "N": dict(kg=1, m=1, s=-2), "N/m": dict(kg=1, s=-2), "N.s/m": dict(kg=1, s=-1),
         "N.m": dict(kg=1, m=2, s=-2)}


def parameter_sets(clearances=PAPER_OUTER_CLEARANCES, start_rpm=20e3, end_rpm=250e3, ramp_time=1.0,
                   perturbation=0.05, system=None):
    """Parameter sets of the turbocharger FMUs, one per outer clearance.

    Initial states come from the method-J equilibrium at the start speed (journals and rings offset in +x by
    ``perturbation`` × clearance, as in :func:`frbmodel.nonlinear.runup.runup`).

    Parameters
    ----------
    clearances : sequence of float
        Outer-film radial clearances [m] of both bearings; set ``co<c in µm>`` each (``co36`` for 36e-6).
    start_rpm, end_rpm : float
        Speed ramp of the rotor FMU [rpm] (written in rad/s).
    ramp_time : float
        Ramp duration [s].
    perturbation : float
        Initial offset of journals and rings in +x as a fraction of the clearance [-].
    system : Turbocharger, optional
        The system the rotor FMU is built for (default: the paper's Table 2 turbocharger): its bearings name the
        bearing components and give the films and rings, each set with its outer clearances set to one of
        ``clearances``.

    Returns
    -------
    dict
        ``{set name: {component: {parameter: (type, value, unit)}}}`` with SSP types ``"Real"`` /
        ``"String"`` and SI units (None for strings).
    """
    base = _table2(system)
    sets = {}
    for c in clearances:
        tc = base.with_outer_clearance(c)
        eq = equilibrium(tc, "J", start_rpm)
        name = f"co{c * 1e6:.0f}"
        comp = {"rotor": {"speed_start": ("Real", rpm_to_rad_s(start_rpm), "rad/s"),
                          "speed_end": ("Real", rpm_to_rad_s(end_rpm), "rad/s"),
                          "ramp_time": ("Real", ramp_time, "s"), "gravity": ("Real", tc.gravity, "m/s2")}}
        w0 = rpm_to_rad_s(start_rpm)
        for (inst, prefix), b, e in zip(bearing_components(tc), tc.bearings, eq.bearings):
            jx = float(e.journal[0] + perturbation * (b.inner.clearance + b.outer.clearance))
            rx = float(e.ring[0] + perturbation * b.outer.clearance)
            comp["rotor"][f"{prefix}.journal_x0"] = ("Real", jx, "m")
            comp["rotor"][f"{prefix}.journal_y0"] = ("Real", float(e.journal[1]), "m")
            # start values of the coupling inputs consistent with the initial state, so that a master that
            # steps before its first exchange (e.g. libcosim) starts from the same point
            bc = BearingComponent(b, tc.film_model)
            bc.ring[:] = [rx, e.ring[1], 0.0, 0.0, e.ring_speed]
            F, K, C, _ = bc.outputs([jx, e.journal[1], 0.0, 0.0], w0)
            torque, _ = bc.losses([jx, e.journal[1], 0.0, 0.0], w0)
            for q, val in zip(("x", "y", "vx", "vy"), (jx, float(e.journal[1]), 0.0, 0.0)):
                comp["rotor"][f"{prefix}.journal_ref.{q}"] = ("Real", val, "m" if len(q) == 1 else "m/s")
            comp["rotor"][f"{prefix}.force_end.x"] = ("Real", float(F[0]), "N")
            comp["rotor"][f"{prefix}.force_end.y"] = ("Real", float(F[1]), "N")
            comp["rotor"][f"{prefix}.force.x"] = ("Real", float(F[0]), "N")
            comp["rotor"][f"{prefix}.force.y"] = ("Real", float(F[1]), "N")
            for i, qi in enumerate("xy"):
                for k, qk in enumerate("xy"):
                    comp["rotor"][f"{prefix}.stiffness.{qi}{qk}"] = ("Real", float(K[i, k]), "N/m")
                    comp["rotor"][f"{prefix}.damping.{qi}{qk}"] = ("Real", float(C[i, k]), "N.s/m")
            comp["rotor"][f"{prefix}.torque"] = ("Real", float(torque), "N.m")
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


def _q(ns, tag):
    """Qualified XML tag ``{namespace}tag``."""
    return f"{{{NS[ns]}}}{tag}"


def _ssd_tree(bound_set, step_size, stop_time, tc=None):
    """SSD of the system ``tc`` (default Table 2) whose components bind ``resources/<bound_set>_<component>.ssv``."""
    comps = [("rotor", "TurbochargerRotor")] + [(inst, "FloatingRingBearing") for inst, _ in bearing_components(tc)]
    return ssd_tree("turbocharger", "Turbocharger rotor on two floating-ring bearings (frbmodel), interface-Jacobian "
                    "coupling", comps, connections(tc), bound_set, step_size, stop_time)


def ssd_tree(name, description, comps, cons, bound_set, step_size, stop_time, unit=None):
    """A flat SSD: components ``comps`` [(name, FMU model identifier)] with the connectors of the connections
    ``cons`` [(start element, start connector, end element, end connector)], each component binding
    ``resources/<bound_set>_<component>.ssv``, a default experiment to ``stop_time`` with the OSP fixed-step
    annotation ``step_size`` [s] (so that libcosim runs it unchanged). ``unit(connector)``: a connector's unit
    (default: the split system's, :func:`_unit`)."""
    unit = unit or _unit
    root = ET.Element(_q("ssd", "SystemStructureDescription"), {"version": "1.0", "name": name})
    system = ET.SubElement(root, _q("ssd", "System"), {"name": name, "description": description})
    elements = ET.SubElement(system, _q("ssd", "Elements"))
    for comp, fmu in comps:
        el = ET.SubElement(elements, _q("ssd", "Component"), {"name": comp, "source": f"resources/{fmu}.fmu",
                                                               "type": "application/x-fmu-sharedlibrary"})
        ctors = ET.SubElement(el, _q("ssd", "Connectors"))
        for s_el, s_c, e_el, e_c in cons:
            for el_name, c_name, kind in ((s_el, s_c, "output"), (e_el, e_c, "input")):
                if el_name == comp:
                    ce = ET.SubElement(ctors, _q("ssd", "Connector"), {"name": c_name, "kind": kind})
                    ET.SubElement(ce, _q("ssc", "Real"), {"unit": unit(c_name)})
        pb = ET.SubElement(el, _q("ssd", "ParameterBindings"))
        ET.SubElement(pb, _q("ssd", "ParameterBinding"), {"source": f"resources/{bound_set}_{comp}.ssv"})
    cs = ET.SubElement(system, _q("ssd", "Connections"))
    for s_el, s_c, e_el, e_c in cons:
        ET.SubElement(cs, _q("ssd", "Connection"), {"startElement": s_el, "startConnector": s_c,
                                                    "endElement": e_el, "endConnector": e_c})
    used = sorted({unit(c) for s_el, s_c, e_el, e_c in cons for c in (s_c, e_c)})
    units = ET.SubElement(root, _q("ssd", "Units"))
    for uname in used:
        u = ET.SubElement(units, _q("ssc", "Unit"), {"name": uname})
        ET.SubElement(u, _q("ssc", "BaseUnit"), {k: str(v) for k, v in UNITS[uname].items()})
    de = ET.SubElement(root, _q("ssd", "DefaultExperiment"), {"startTime": "0", "stopTime": repr(float(stop_time))})
    ann = ET.SubElement(ET.SubElement(de, _q("ssd", "Annotations")), _q("ssc", "Annotation"),
                        {"type": "com.opensimulationplatform"})
    alg = ET.SubElement(ann, _q("osp", "Algorithm"))
    ET.SubElement(alg, _q("osp", "FixedStepAlgorithm"), {"baseStepSize": repr(float(step_size))})
    ET.indent(root)
    return ET.ElementTree(root)


def _ssv_tree(set_name, params):
    """``ssv:ParameterSet`` named ``set_name`` of ``{parameter: (type, value, unit)}``."""
    ps = ET.Element(_q("ssv", "ParameterSet"), {"version": "1.0", "name": set_name})
    pars = ET.SubElement(ps, _q("ssv", "Parameters"))
    for pname, (typ, val, _) in params.items():
        p = ET.SubElement(pars, _q("ssv", "Parameter"), {"name": pname})
        ET.SubElement(p, _q("ssv", typ), {"value": repr(float(val)) if typ == "Real" else str(val)})
    ET.indent(ps)
    return ET.ElementTree(ps)


def write_ssp(out_dir="ssp", step_size=1e-5, stop_time=1.0, system=None, **kw):
    """Write the SSP folder: the SSDs (one variant per parameter set) and the parameter sets.

    ``SystemStructure.ssd`` (the default variant) binds the first parameter set, ``<set>.ssd`` each further
    one; ``resources/<set>_<component>.ssv`` hold the values. The FMUs (``resources/*.fmu``) are added by
    :func:`frbmodel.cosim.build.build_fmus`.

    Parameters
    ----------
    out_dir : str or Path
        Folder to write (created if needed).
    step_size : float
        Macro step of the OSP fixed-step annotation [s].
    stop_time : float
        Stop time of the default experiment [s].
    system : Turbocharger, optional
        The system the rotor FMU is built for (default: the paper's Table 2 turbocharger): its bearings name the
        bearing components and the rotor's ``<bearing>_bearing.*`` connectors (see :func:`parameter_sets`).
    **kw
        Passed to :func:`parameter_sets` (``clearances``, ``start_rpm``, ...).

    Returns
    -------
    list of Path
        The written files, SSDs first.
    """
    return _write_sets(out_dir, parameter_sets(system=system, **kw),
                       lambda set_name: _ssd_tree(set_name, step_size, stop_time, system))


def _write_sets(out_dir, sets, ssd_of):
    """Write one SSD per parameter set (``ssd_of(set_name)``; the first as the default SSD) and each set's SSV per
    component under ``resources/``; the written paths, SSDs first."""
    out = Path(out_dir)
    (out / "resources").mkdir(parents=True, exist_ok=True)
    for k, v in NS.items():
        ET.register_namespace(k, v)
    paths = []
    for i, set_name in enumerate(sets):
        paths.append(out / (DEFAULT_SSD if i == 0 else f"{set_name}.ssd"))
        ssd_of(set_name).write(paths[-1], xml_declaration=True, encoding="UTF-8")
    for set_name, comps_p in sets.items():
        for comp, params in comps_p.items():
            paths.append(out / "resources" / f"{set_name}_{comp}.ssv")
            _ssv_tree(set_name, params).write(paths[-1], xml_declaration=True, encoding="UTF-8")
    return paths


#: the example system of the turbocharger FMU: its components and connections (the turbine drives the rotor through
#: the engine side's drive torque, the engine side reads the rotor speed)
ENGINE_COMPONENTS = (("engine", "EngineTorque"), ("turbocharger", "FloatingRingTurbocharger"))
ENGINE_CONNECTIONS = (("turbocharger", "rotor_speed", "engine", "rotor_speed"),
                      ("engine", "drive_torque", "turbocharger", "drive_torque"))
#: the example engine's parameters (fmu_src/EngineTorque.py: a torque balance at 18 000 rad/s)
ENGINE_PARAMETERS = {"turbine_torque_0": 2.0, "turbine_torque_slope": 2.0 / 30000.0,
                     "compressor_coefficient": 0.8 / 18000.0 ** 2, "pulsation": 0.3, "firing_frequency": 100.0}


def engine_parameter_sets(clearances=(DEFAULT_OUTER_CLEARANCE_M,), start_rpm=20e3, system=None):
    """Parameter sets of the engine + turbocharger example, one per outer clearance (``co36`` ...): the engine's
    parameters and start speed, the turbocharger torque-driven from ``start_rpm`` with both outer films at the
    clearance.

    Returns
    -------
    dict
        ``{set name: {component: {parameter: (type, value, unit)}}}``.
    """
    tc = _table2(system)
    w0 = rpm_to_rad_s(start_rpm)
    units = {"turbine_torque_0": "N.m", "turbine_torque_slope": "N.m.s/rad", "compressor_coefficient": "N.m.s2/rad2",
             "pulsation": "1", "firing_frequency": "Hz"}
    sets = {}
    for c in clearances:
        engine = {k: ("Real", v, units[k]) for k, v in ENGINE_PARAMETERS.items()}
        engine["rotor_speed"] = ("Real", w0, "rad/s")
        turbo = {"speed_source": ("String", "torque", None), "speed_start": ("Real", w0, "rad/s")}
        for b in tc.bearings:
            turbo[f"{b.name}_bearing.outer.clearance"] = ("Real", float(c), "m")
        sets[f"co{round(c * 1e6)}"] = {"engine": engine, "turbocharger": turbo}
    return sets


def write_engine_ssp(out_dir="ssp/engine", step_size=1e-3, stop_time=1.0, system=None, **kw):
    """Write the SSP folder of the example: the example engine (EngineTorque FMU) driving the turbocharger FMU
    (FloatingRingTurbocharger) through its drive torque, at a system-model step (default 1 ms), one SSD variant per
    parameter set (:func:`engine_parameter_sets`; ``**kw`` go there). The FMUs are added by
    :func:`frbmodel.cosim.build.build_fmus`.

    Returns
    -------
    list of Path
        The written files, SSDs first.
    """
    return _write_sets(out_dir, engine_parameter_sets(system=system, **kw),
                       lambda set_name: ssd_tree("engine_turbocharger",
                                                 "Example engine side driving the turbocharger FMU (frbmodel)",
                                                 ENGINE_COMPONENTS, ENGINE_CONNECTIONS, set_name, step_size,
                                                 stop_time))


@dataclass
class SSPSystem:
    """A parsed SSP: components, connections, parameter sets (one per SSD variant), step and stop time.

    Read from an ``.ssp`` archive, the object owns the temporary folder the archive was extracted to
    (:attr:`root`, holding the FMUs of :attr:`components`): :meth:`close` or the end of a ``with`` block deletes
    it; without either, garbage collection of the object (or the end of the interpreter) does. Keep the object
    while the FMU paths are in use.

    Attributes
    ----------
    root : Path
        Folder holding the SSDs (an archive is extracted to a temporary folder, see :meth:`close`).
    components : dict
        ``{component name: FMU path}``.
    connections : list of tuple
        ``(start element, start connector, end element, end connector)``.
    parameter_files : dict
        ``{set name: {component: tuple of .ssv paths}}``, the files the set's SSD binds, in binding order.
    step_size : float or None
        Macro step of the OSP fixed-step annotation [s].
    stop_time : float or None
        Stop time of the default experiment [s].
    parameter_sets : dict
        ``{set name: {component: {parameter: (type, value)}}}`` (bindings of a component merged in order,
        later ones overriding earlier ones, as SSP 1.0 prescribes).
    default_set : str or None
        The set bound by ``SystemStructure.ssd``.
    source : Path or None
        The folder or archive that was read (named in error messages).
    """

    root: Path
    components: dict
    connections: list
    parameter_files: dict = field(default_factory=dict)
    step_size: float | None = None
    stop_time: float | None = None
    parameter_sets: dict = field(default_factory=dict)
    default_set: str | None = None
    source: Path | None = None
    _finalizer: weakref.finalize | None = field(default=None, init=False, repr=False, compare=False)

    def _own(self, folder):
        """Take ownership of the temporary folder ``folder``: delete it on :meth:`close` or collection."""
        self._finalizer = weakref.finalize(self, shutil.rmtree, str(folder), ignore_errors=True)

    @property
    def temporary(self) -> bool:
        """True while :attr:`root` is a temporary extraction of an archive that :meth:`close` will delete."""
        return self._finalizer is not None and self._finalizer.alive

    def close(self):
        """Delete the temporary folder of an extracted archive (no effect for an SSP folder; idempotent).

        The paths in :attr:`components` and :attr:`parameter_files` of an archive no longer exist afterwards.
        """
        if self._finalizer is not None:
            self._finalizer()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False

    def parameters(self, set_name=None):
        """Parameter values of one set.

        Parameters
        ----------
        set_name : str, optional
            Name of the set (``co36``, ...); default: :attr:`default_set`.

        Returns
        -------
        dict
            ``{component: {parameter: (type, value)}}`` (a copy).

        Raises
        ------
        ParameterError
            The SSP has no such set; the message names the SSP, the set and the available sets.
        """
        name = self.default_set if set_name is None else set_name
        if name not in self.parameter_sets:
            raise ParameterError(f"parameter set = {name!r} is not in SSP {str(self.source or self.root)!r}; "
                                 f"available sets: {sorted(self.parameter_sets)}")
        return {c: dict(p) for c, p in self.parameter_sets[name].items()}


def _value(typ, text, where):
    """Python value of an SSV value attribute of SSP type ``typ``; ``where`` names it in errors."""
    try:
        if typ == "Real":
            return float(text)
        if typ == "Integer":
            return int(text)
        if typ == "Boolean":
            if text.lower() not in ("true", "false", "1", "0"):
                raise ValueError(text)
            return text.lower() in ("true", "1")
    except (TypeError, ValueError, AttributeError):
        raise ParameterError(f"{where} = {text!r} is invalid: expected an SSP {typ} value") from None
    return text


def _parameter_set(element, what):
    """(name, {parameter: (type, value)}) of an ``ssv:ParameterSet`` element; ``what`` names it in errors."""
    out = {}
    for p in element.iter(_q("ssv", "Parameter")):
        for child in p:
            typ = child.tag.split("}")[1]
            out[p.get("name")] = (typ, _value(typ, child.get("value"), f"{what}: parameter {p.get('name')!r}"))
    return element.get("name"), out


def _parse(path, what):
    """Root element of the XML file ``path`` or :class:`ParameterError` naming ``what``."""
    try:
        return ET.parse(path).getroot()
    except ET.ParseError as exc:
        raise ParameterError(f"{what} {str(path)!r} is not well-formed XML: {exc}") from None


def read_ssv(path):
    """Parameters of an SSP parameter-set file.

    Parameters
    ----------
    path : str or Path
        ``.ssv`` file (``ssv:ParameterSet``).

    Returns
    -------
    dict
        ``{parameter: (type, value)}``: type ``"Real"`` (float), ``"Integer"`` (int), ``"Boolean"`` (bool) or
        ``"String"``.
    """
    return _parameter_set(_parse(path, "parameter set"), f"parameter set {str(path)!r}")[1]


def _binding_values(binding, ssd_path, where):
    """(set name, {parameter: (type, value)}, source path or None) of one ``ssd:ParameterBinding``."""
    typ = binding.get("type", PARAMETER_SET_TYPE)
    if typ != PARAMETER_SET_TYPE or binding.get("sourceBase", "SSD") != "SSD" \
            or binding.find("ssd:ParameterMapping", NS) is not None:
        raise ParameterError(f"{where}: only ParameterBindings of type {PARAMETER_SET_TYPE} resolved against the "
                             "SSD, without ParameterMapping, are supported")
    source = binding.get("source")
    if source:
        path = ssd_path.parent / source
        if not path.is_file():
            raise ParameterError(f"{where} binds {source!r}, which is not in the SSP")
        name, values = _parameter_set(_parse(path, "parameter set"), f"{where} binds {source!r}")
    else:
        inline = binding.find("ssd:ParameterValues/ssv:ParameterSet", NS)
        if inline is None:
            raise ParameterError(f"{where}: a ParameterBinding has neither a source nor inline ParameterValues")
        path = None
        name, values = _parameter_set(inline, f"{where} inline values")
    prefix = binding.get("prefix", "")
    return name, {prefix + k: v for k, v in values.items()}, path


def _bound_set(ssd_root, ssd_path):
    """(set name, {component: values}, {component: tuple of .ssv paths}) that one SSD binds."""
    if ssd_root.find("ssd:System/ssd:ParameterBindings", NS) is not None:
        raise ParameterError(f"{ssd_path.name}: system-level ParameterBindings are not supported; bind the "
                             "parameter sets to the components")
    values, files, names = {}, {}, set()
    for comp in ssd_root.iterfind("ssd:System/ssd:Elements/ssd:Component", NS):
        cname = comp.get("name")
        values[cname], files[cname] = {}, []
        for b in comp.iterfind("ssd:ParameterBindings/ssd:ParameterBinding", NS):
            name, vals, path = _binding_values(b, ssd_path, f"{ssd_path.name} component {cname!r}")
            values[cname].update(vals)  # SSP 1.0: later bindings override earlier ones
            names.add(name)
            if path is not None:
                files[cname].append(path)
        files[cname] = tuple(files[cname])
    # the set is named by its parameter sets; bindings of differently named sets name it by the variant's file
    set_name = names.pop() if len(names) == 1 and None not in names else ssd_path.stem
    return set_name, values, files


def _structure(ssd_root, folder, ssd_name):
    """({component: FMU path}, [(start element, start connector, end element, end connector)])."""
    comps = {}
    for c in ssd_root.iterfind("ssd:System/ssd:Elements/ssd:Component", NS):
        if not c.get("source"):
            raise ParameterError(f"{ssd_name}: component {c.get('name')!r} has no source (its FMU file)")
        comps[c.get("name")] = folder / c.get("source")
    cons = [(c.get("startElement"), c.get("startConnector"), c.get("endElement"), c.get("endConnector"))
            for c in ssd_root.iterfind("ssd:System/ssd:Connections/ssd:Connection", NS)]
    for s_el, s_c, e_el, e_c in cons:
        for el in (s_el, e_el):
            if el not in comps:
                raise ParameterError(f"SSP connection {s_el}.{s_c} -> {e_el}.{e_c} names an unknown component "
                                     f"{el!r}; components are {sorted(comps)}")
    return comps, cons


def _check_single_feeds(cons, ssd_name):
    """ParameterError when an input is the end of more than one connection (a second one overwrote the first)."""
    sources = {}
    for s_el, s_c, e_el, e_c in cons:
        sources.setdefault((e_el, e_c), []).append(f"{s_el}.{s_c}")
    fed_twice = {k: v for k, v in sources.items() if len(v) > 1}
    if fed_twice:
        (e_el, e_c), srcs = next(iter(fed_twice.items()))
        raise ParameterError(f"{ssd_name}: the input {e_el}.{e_c} is the end of {len(srcs)} connections (from "
                             f"{', '.join(srcs)}); an input takes one connection ({len(fed_twice)} inputs are fed "
                             "more than once)")


def _extract(path):
    """Temporary folder with the extracted archive ``path`` (deleted again if the extraction fails)."""
    tmp = Path(tempfile.mkdtemp(prefix="frb_ssp_"))
    try:
        with zipfile.ZipFile(path) as z:
            z.extractall(tmp)
    except zipfile.BadZipFile:
        shutil.rmtree(tmp, ignore_errors=True)
        raise ParameterError(f"SSP = {str(path)!r} is not a valid .ssp (zip) archive; pass an .ssp archive or "
                             "an SSP folder (SystemStructure.ssd + resources/)") from None
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return tmp


def _check_fmus(comps, folder, source):
    """ParameterError naming the SSP, the component and the file if a component's FMU is not in the SSP."""
    for name, fmu in comps.items():
        if not fmu.is_file():
            rel = fmu.relative_to(folder).as_posix() if fmu.is_relative_to(folder) else str(fmu)
            raise ParameterError(f"SSP {str(source)!r}: component {name!r} needs the FMU {rel!r}, which is not in "
                                 "the SSP; `frb build-fmus` packs build/turbocharger.ssp with both FMUs")


def read_ssp(path, require_fmus=True) -> SSPSystem:
    """Parse an SSP folder or ``.ssp`` archive, its parameter sets from the SSDs' ParameterBindings.

    ``SystemStructure.ssd`` gives the components, connections, step and stop time and the default set; every
    further ``.ssd`` at the root is a variant that must describe the same system and gives one more set.

    Parameters
    ----------
    path : str or Path
        Folder or ``.ssp`` archive (extracted to a temporary folder that the returned object owns: use it in a
        ``with`` block or call :meth:`SSPSystem.close` to delete it; garbage collection deletes it otherwise).
    require_fmus : bool
        Check that the FMU file of every component is in the SSP (False: read the SSDs and parameter sets of
        a folder without FMUs, such as the repository's ``ssp/``).

    Returns
    -------
    SSPSystem

    Raises
    ------
    ParameterError
        A missing path, a file that is not a zip archive, a missing SystemStructure.ssd, malformed XML or
        parameter values, a component whose FMU is not in the SSP (the message names the SSP, the component
        and the file), a connection to an unknown component, a variant that differs in structure, two
        variants binding sets of the same name, or an unsupported kind of binding.
    """
    source = Path(path)
    if not source.exists():
        raise ParameterError(f"SSP = {str(source)!r} does not exist")
    if source.is_dir():
        return _read_folder(source, source, require_fmus)
    tmp = _extract(source)
    try:
        system = _read_folder(tmp, source, require_fmus)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    system._own(tmp)
    return system


def _read_folder(folder, source, require_fmus):
    """SSPSystem of the SSP folder ``folder`` (read from ``source``, named in messages)."""
    ssd = folder / DEFAULT_SSD
    if not ssd.is_file():
        raise ParameterError(f"SSP {str(source)!r} has no {DEFAULT_SSD} at its root")
    root = _parse(ssd, DEFAULT_SSD + " of SSP")
    comps, cons = _structure(root, folder, DEFAULT_SSD)
    if require_fmus:
        _check_fmus(comps, folder, source)
    sets, files = {}, {}
    for f in [ssd] + sorted(p for p in folder.glob("*.ssd") if p.name != DEFAULT_SSD):
        r = root if f == ssd else _parse(f, "SSD variant")
        if f != ssd and _structure(r, folder, f.name) != (comps, cons):
            raise ParameterError(f"SSP {str(source)!r}: variant {f.name} has other components or connections "
                                 f"than {DEFAULT_SSD}; only parameter variants are supported")
        name, values, paths = _bound_set(r, f)
        if name in sets:
            raise ParameterError(f"SSP {str(source)!r}: {f.name} binds parameter set {name!r}, which another "
                                 "SSD binds already")
        sets[name], files[name] = values, paths
    _check_single_feeds(cons, DEFAULT_SSD)
    step = stop = None
    fsa = root.find(".//osp:FixedStepAlgorithm", NS)
    if fsa is not None:
        step = _value("Real", fsa.get("baseStepSize"), f"{DEFAULT_SSD} FixedStepAlgorithm baseStepSize")
    de = root.find("ssd:DefaultExperiment", NS)
    if de is not None and de.get("stopTime"):
        stop = _value("Real", de.get("stopTime"), f"{DEFAULT_SSD} DefaultExperiment stopTime")
    return SSPSystem(folder, comps, cons, files, step, stop, sets, next(iter(sets)), source)


__all__ = ["write_ssp", "write_engine_ssp", "read_ssp", "read_ssv", "connections", "bearing_components",
           "parameter_sets", "engine_parameter_sets", "ssd_tree", "SSPSystem"]
