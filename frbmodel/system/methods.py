"""The nine bearing-modelling methods A–J as data (the paper's Table 1).

Each method is a :class:`Method` record naming its ingredients; :mod:`frbmodel.linear.equilibrium` and
:mod:`frbmodel.linear.assembly` interpret the records, so there is one pipeline, not nine.

======  =========  ==================  ==================  ======  ==========================================
letter  ring DoFs  support             equilibrium         RSR     meaning
======  =========  ==================  ==================  ======  ==========================================
A       no         isotropic_spring    —                   —       journal on springs k (default 1e6 N/m)
B       no         orthotropic_spring  —                   —       springs kx, ky (1e6, 2e6 N/m)
C       no         outer_film          outer_film          eq6     inner film rigid; outer film K, C only
D       no         series_films        uncoupled           eq6     inner & outer film K, C element-wise in series
E       yes        ring_springs        —                   —       ring on springs k inside and outside, undamped
F       yes        films               uncoupled           eq6     both films, single-film equilibria (closed form)
G       yes        films               coupled             eq6     both films, equilibrium (28)–(31) as one system
I       yes        films               petroff             eq7     ring speed from eq. (7) at the solved ε's
J       yes        films               torque              torque  ring speed from the full torque balance (32)
======  =========  ==================  ==================  ======  ==========================================

"Ring DoFs" means the global system is the paper's eq. (8) (rotor + ring lateral DoFs, film coupling
(27)); otherwise it is eq. (3) (rotor DoFs only). For C and D (no ring DoFs) the ring mass is lumped onto
the journal node, since the ring then moves with the journal.
"""
from __future__ import annotations

from dataclasses import dataclass

from ..core.errors import ParameterError, check_real, check_real_array, check_speeds_in_range

#: stiffest linear spring of methods A, B, E and the run-up's ``linear_springs`` [N/m]. The supports are rigid there:
#: the Table 2 rotor's first four frequencies at 1e15 N/m are those at 1e18 within 3e-8 (methods A, B, E); stiffer
#: springs only lose digits to round-off in the state matrix (method B's first mode 4e-6 off at 1e25, 3 % at 1e30)
#: until, at 1e40, every method's modes are wrong without a warning (method A's first at 251 Hz instead of 525 Hz)
MAX_SPRING_N_M = 1e15


def check_spring(name, value):
    """``float(value)`` of a linear spring stiffness [N/m] in 0 < k <= :data:`MAX_SPRING_N_M`, else a
    :class:`ParameterError` naming ``name``, the value and the range (strings are refused, not converted).

    Examples
    --------
    >>> try:
    ...     check_spring("method A k", 1e40)
    ... except ParameterError as exc:
    ...     print(exc)  # doctest: +ELLIPSIS
    method A k = 1e+40 N/m is invalid: valid range 0 < k <= 1e+15 N/m (a rigid support; stiffer springs lose ...
    """
    k = check_real(name, value, "N/m", minimum=0.0)
    if k > MAX_SPRING_N_M:
        raise ParameterError(f"{name} = {value!r} N/m is invalid: valid range 0 < k <= {MAX_SPRING_N_M:g} N/m (a rigid "
                             "support; stiffer springs lose the rotor's modes to round-off)")
    return k


@dataclass(frozen=True)
class Method:
    """Ingredients of one bearing-modelling method (a row of the paper's Table 1).

    Attributes
    ----------
    letter : str
        A, B, C, D, E, F, G, I or J.
    title : str
        One-line description.
    ring_dofs : bool
        The global system has ring (x, y) DoFs (the paper's eq. (8)).
    support : str
        isotropic_spring | orthotropic_spring | outer_film | series_films | ring_springs | films.
    equilibrium : str or None
        None | outer_film | uncoupled | coupled | petroff | torque.
    rsr : str or None
        None | eq6 | eq7 | torque.
    parameters, defaults : tuple
        Names and default values [N/m] of the keyword parameters the method takes.

    Examples
    --------
    >>> METHODS["B"].options(kx=3e6)
    {'kx': 3000000.0, 'ky': 2000000.0}
    """

    letter: str
    title: str
    ring_dofs: bool
    support: str  # isotropic_spring | orthotropic_spring | outer_film | series_films | ring_springs | films
    equilibrium: str | None  # None | outer_film | uncoupled | coupled | petroff | torque
    rsr: str | None  # None | eq6 | eq7 | torque
    parameters: tuple = ()  # names of the keyword parameters it takes, with defaults
    defaults: tuple = ()

    @property
    def needs_films(self) -> bool:
        """True if the method linearizes oil films (needs a positive rotor speed)."""
        return self.equilibrium is not None

    def check_speeds(self, speeds_rpm, name="speeds_rpm"):
        """Rotor speeds [rpm] this method can take, as a float array, or a :class:`ParameterError` naming ``name``:
        a non-empty 1-D list of finite speeds within the model's range, each > 0 for a film method (the one speed
        check of the linear analyses: Campbell, unbalance, linear systems, FMU linearization).

        Parameters
        ----------
        speeds_rpm : float or sequence of float
            Rotor speeds [rpm].
        name : str
            The option or argument named in the error.

        Returns
        -------
        numpy.ndarray
            The speeds [rpm] as floats.

        Examples
        --------
        >>> METHODS["J"].check_speeds([2e3, 1e3]).tolist()
        [2000.0, 1000.0]
        >>> try:
        ...     METHODS["J"].check_speeds([0.0, 1e3])
        ... except ParameterError as exc:
        ...     print(exc)
        speeds_rpm contains 0.0 rpm, invalid for method J: linearized films need speeds > 0
        """
        import numpy as np


        speeds = np.atleast_1d(check_real_array(name, speeds_rpm, "rpm"))
        if speeds.ndim != 1 or speeds.size == 0:
            raise ParameterError(f"{name} = {speeds_rpm!r} is invalid: a non-empty 1-D list of finite speeds [rpm]")
        if self.needs_films and np.any(speeds <= 0):
            raise ParameterError(f"{name} contains {float(speeds[speeds <= 0][0])!r} rpm, invalid for method "
                                 f"{self.letter}: linearized films need speeds > 0")
        check_speeds_in_range(name, speeds)
        return speeds

    def options(self, **kwargs) -> dict:
        """Merge user keyword parameters with the defaults.

        Parameters
        ----------
        **kwargs
            Spring stiffnesses ``k``, ``kx``, ``ky`` [N/m] the method takes (None: default).

        Returns
        -------
        dict
            Every parameter of the method with its value [N/m].

        Raises
        ------
        ParameterError
            A parameter the method does not take, or a value that is not a finite real number in 0 < k <=
            :data:`MAX_SPRING_N_M` (strings are refused, not converted).
        """
        out = dict(zip(self.parameters, self.defaults))
        for k, v in kwargs.items():
            if v is None:
                continue
            if k not in out:
                raise ParameterError(f"parameter {k!r} is not used by method {self.letter}; "
                                     f"valid: {list(self.parameters) or 'none'}")
            out[k] = check_spring(f"method {self.letter} {k}", v)
        return out


METHODS = {m.letter: m for m in (
    Method("A", "isotropic linear springs", False, "isotropic_spring", None, None, ("k",), (1e6,)),
    Method("B", "orthotropic linear springs", False, "orthotropic_spring", None, None, ("kx", "ky"), (1e6, 2e6)),
    Method("C", "outer film only (inner film rigid), RSR eq. (6)", False, "outer_film", "outer_film", "eq6"),
    Method("D", "inner and outer film in series, element-wise, RSR eq. (6)", False, "series_films", "uncoupled", "eq6"),
    Method("E", "ring DoFs on linear springs (inner k, outer k), undamped", True, "ring_springs", None, None,
           ("k",), (1e6,)),
    Method("F", "ring DoFs, both films, uncoupled film equilibria, RSR eq. (6)", True, "films", "uncoupled", "eq6"),
    Method("G", "ring DoFs, both films, coupled equilibrium (28)-(31), RSR eq. (6)", True, "films", "coupled", "eq6"),
    Method("I", "ring DoFs, both films, coupled equilibrium, RSR eq. (7)", True, "films", "petroff", "eq7"),
    Method("J", "ring DoFs, both films, coupled equilibrium with torque balance (32)", True, "films", "torque",
           "torque"),
)}

#: methods with a film equilibrium
EQUILIBRIUM_METHODS = tuple(k for k, m in METHODS.items() if m.needs_films)


def get_method(letter) -> Method:
    """Look up a method by letter (case-insensitive).

    Parameters
    ----------
    letter : str
        One of A, B, C, D, E, F, G, I, J.

    Returns
    -------
    Method

    Examples
    --------
    >>> get_method("j").ring_dofs
    True
    """
    key = str(letter).strip().upper()
    if key not in METHODS:
        raise ParameterError(f"method = {letter!r} is unknown; valid methods are {', '.join(METHODS)} "
                             "(the paper has no H)")
    return METHODS[key]
