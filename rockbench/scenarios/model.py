"""What is simulated: blocks, stacks, contact and the scenario that ties them together.

Axes (DESIGN.md): z up, rocking in the x–z plane, θ = rotation about +y, positive
when a block's top moves toward +x (pivoting on its +x bottom edge).
A chamfer c moves each rocking pivot inward by c: the pivots are the corners of
the chamfered bottom face, at half-width b − c on the face itself.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields
from typing import Any

import numpy as np

from rockbench.errors import ScenarioError
from rockbench.scenarios import checks
from rockbench.scenarios.excitation import Excitation, Free

__all__ = ["Block", "Stack", "Contact", "Scenario", "RockingProperties"]


def _check(value: Any, what: str, *, low: float | None = 0.0, strict: bool = True,
           high: float | None = None, unit: str = "") -> float:
    """Validate a finite number (never a string or boolean) in a range; return it as float."""
    return checks.number(value, what, low=low, strict=strict, high=high, unit=unit)


@dataclass(frozen=True)
class RockingProperties:
    """Rocking constants of a rigid body about a corner pivot.

    Attributes
    ----------
    lam : float
        Critical (slenderness) angle λ = atan(b/h) in rad, b the pivot
        half-width and h the height of the centre of gravity above the pivots.
    R : float
        Distance pivot–centre of gravity (m).
    p : float
        Frequency parameter sqrt(m g R / I_O) (rad/s).
    eta : float
        Housner's angular-velocity ratio at impact, 1 − 2 m b² / I_O.
    I_O : float
        Moment of inertia about the pivot (kg m²).
    """

    lam: float
    R: float
    p: float
    eta: float
    I_O: float

    @property
    def uplift_acceleration(self) -> float:
        """Static uplift threshold g tan λ divided by g (i.e. tan λ)."""
        return math.tan(self.lam)


def _rocking(m: float, b: float, h: float, i_c: float, g: float) -> RockingProperties:
    r = math.hypot(b, h)
    i_o = float(i_c) + m * r * r
    return RockingProperties(
        lam=math.atan2(b, h), R=r, p=math.sqrt(m * g * r / i_o),
        eta=1.0 - 2.0 * m * b * b / i_o, I_O=i_o,
    )


@dataclass(frozen=True)
class Block:
    """A rectangular rigid block, optionally chamfered on its rocking edges.

    Parameters
    ----------
    width : float
        Size along x, the rocking direction (m).
    depth : float
        Size along y, out of plane (m).
    height : float
        Size along z (m).
    density : float, optional
        kg/m³. Give exactly one of ``density`` and ``mass``.
    mass : float, optional
        kg.
    chamfer : float
        45° cut on the four edges parallel to y (m), smaller than half the width
        and half the height. Mass and inertia of the cut corners are neglected.
    """

    width: float
    depth: float
    height: float
    density: float | None = None
    mass: float | None = None
    chamfer: float = 0.0

    def __post_init__(self) -> None:
        for name in ("width", "depth", "height"):
            object.__setattr__(self, name, _check(getattr(self, name), f"block {name}",
                                                  unit="m"))
        if (self.density is None) == (self.mass is None):
            raise ScenarioError("block needs exactly one of 'density' and 'mass'")
        if self.density is not None:
            object.__setattr__(self, "density", _check(self.density, "block density",
                                                       unit="kg/m³"))
        else:
            object.__setattr__(self, "mass", _check(self.mass, "block mass", unit="kg"))
        c = _check(self.chamfer, "block chamfer", strict=False, unit="m")
        if c >= 0.5 * min(self.width, self.height):
            raise ScenarioError(
                f"block chamfer {c} must be smaller than half the width and half the height"
            )
        object.__setattr__(self, "chamfer", c)

    @property
    def volume(self) -> float:
        """Volume of the uncut box (m³)."""
        return self.width * self.depth * self.height

    @property
    def m(self) -> float:
        """Mass in kg."""
        return self.mass if self.mass is not None else self.density * self.volume  # type: ignore[operator]

    @property
    def b(self) -> float:
        """Half-width (m)."""
        return 0.5 * self.width

    @property
    def h(self) -> float:
        """Half-height (m)."""
        return 0.5 * self.height

    @property
    def pivot_half_width(self) -> float:
        """Half-distance between the two rocking pivots, b − chamfer (m)."""
        return self.b - self.chamfer

    @property
    def inertia(self) -> np.ndarray:
        """Principal centroidal moments of inertia (Ixx, Iyy, Izz) of the box (kg m²)."""
        w, d, h, m = self.width, self.depth, self.height, self.m
        return np.array([m * (d * d + h * h), m * (w * w + h * h), m * (w * w + d * d)]) / 12.0

    def rocking(self, g: float = 9.81) -> RockingProperties:
        """Rocking constants λ, R, p, η about its own bottom pivots on a rigid base."""
        return _rocking(self.m, self.pivot_half_width, self.h, self.inertia[1], g)

    def profile(self) -> np.ndarray:
        """Convex outline in the x–z plane about the centroid, counter-clockwise, shape (k, 2)."""
        b, h, c = self.b, self.h, self.chamfer
        if c == 0:
            return np.array([[-b, -h], [b, -h], [b, h], [-b, h]])
        return np.array([
            [-b + c, -h], [b - c, -h], [b, -h + c], [b, h - c],
            [b - c, h], [-b + c, h], [-b, h - c], [-b, -h + c],
        ])

    def to_dict(self) -> dict[str, Any]:
        """Scenario-file representation."""
        d: dict[str, Any] = {"width": self.width, "depth": self.depth, "height": self.height}
        if self.mass is not None:
            d["mass"] = self.mass
        else:
            d["density"] = self.density
        d["chamfer"] = self.chamfer
        return d


@dataclass(frozen=True)
class Stack:
    """Blocks stacked bottom to top, each centred on the one below.

    Parameters
    ----------
    blocks : sequence of Block
        Bottom first.
    offsets : sequence of float, optional
        Horizontal offset (m) of each block's centre from the bottom block's
        centre along x. Only zeros are supported by the analytic models. The
        blocks above each contact must have their common centre of mass
        strictly inside it (between the pivots both faces share), else the
        stack could not stand at rest.
    """

    blocks: tuple[Block, ...]
    offsets: tuple[float, ...] = ()

    def __post_init__(self) -> None:
        blocks = tuple(self.blocks)
        if not blocks:
            raise ScenarioError("a stack needs at least one block")
        if not all(isinstance(b, Block) for b in blocks):
            raise ScenarioError("stack blocks must be Block instances")
        offsets = tuple(_check(o, "stack offset", low=None, unit="m") for o in self.offsets) \
            or (0.0,) * len(blocks)
        if len(offsets) != len(blocks):
            raise ScenarioError(f"stack offsets must be one per block: {len(offsets)} offsets "
                                f"for {len(blocks)} blocks")
        object.__setattr__(self, "blocks", blocks)
        object.__setattr__(self, "offsets", offsets)
        self._check_support()

    def _check_support(self) -> None:
        """Refuse a stack whose upper blocks' centre of mass lies off a contact."""
        ms = [b.m for b in self.blocks]
        for i in range(1, len(self.blocks)):
            lo, up = self.blocks[i - 1], self.blocks[i]
            left = max(self.offsets[i - 1] - lo.pivot_half_width,
                       self.offsets[i] - up.pivot_half_width)
            right = min(self.offsets[i - 1] + lo.pivot_half_width,
                        self.offsets[i] + up.pivot_half_width)
            m_above = sum(ms[i:])
            x_above = sum(m * x for m, x in zip(ms[i:], self.offsets[i:], strict=True)) / m_above
            if not left < x_above < right:
                raise ScenarioError(
                    f"block #{i + 1} is off its support: the centre of mass of the blocks from "
                    f"#{i + 1} up is at x = {x_above:g} m, outside the contact with block #{i} "
                    f"(x from {left:g} to {right:g} m; offsets are from the bottom block's "
                    f"centre)")

    def __len__(self) -> int:
        return len(self.blocks)

    @property
    def total_height(self) -> float:
        """Height of the stack (m)."""
        return sum(b.height for b in self.blocks)

    @property
    def base_z(self) -> np.ndarray:
        """Height of each block's bottom face above the ground when upright (m)."""
        return np.array(self._base_z())

    def _base_z(self) -> list[float]:
        # a running sum in Python floats: a few blocks cost less than NumPy's call overhead
        out, z = [], 0.0
        for b in self.blocks:
            out.append(z)
            z += b.height
        return out

    @property
    def centroids(self) -> np.ndarray:
        """Upright centroid (x, z) of each block, shape (n, 2)."""
        return np.array([(x, z + b.h) for x, z, b in zip(self.offsets, self._base_z(),
                                                          self.blocks, strict=True)])

    def monolithic(self, g: float = 9.81) -> RockingProperties:
        """Rocking constants of the whole stack rocking as one body on the bottom pivots."""
        ms = np.array([b.m for b in self.blocks])
        c = self.centroids
        m = ms.sum()
        xbar = float(ms @ c[:, 0] / m)
        zbar = float(ms @ c[:, 1] / m)
        i_c = sum(b.inertia[1] for b in self.blocks) + float(
            ms @ ((c[:, 0] - xbar) ** 2 + (c[:, 1] - zbar) ** 2)
        )
        return _rocking(m, self.blocks[0].pivot_half_width, zbar, i_c, g)

    def interface(self, i: int, g: float = 9.81) -> RockingProperties:
        """Rocking constants of block ``i`` (i ≥ 1) alone on the block below it.

        The interface pivots sit at b_c = min of the two facing pivot half-widths.
        """
        lo, up = self.blocks[i - 1], self.blocks[i]
        bc = min(lo.pivot_half_width, up.pivot_half_width)
        return _rocking(up.m, bc, up.h, up.inertia[1], g)

    def critical_angle(self, g: float = 9.81) -> float:
        """Smallest critical angle: each block's own (on its support) and the whole stack's."""
        lams = [self.blocks[0].rocking(g).lam]
        lams += [self.interface(i, g).lam for i in range(1, len(self.blocks))]
        if len(self.blocks) > 1:
            lams.append(self.monolithic(g).lam)
        return min(lams)


@dataclass(frozen=True)
class Contact:
    """Contact properties shared by every contact in the scene.

    Parameters
    ----------
    friction : float
        Coulomb coefficient (≥ 0); the paper uses 1.0 (45°).
    restitution : float
        Engines' bounce coefficient in [0, 1].
    eta : float, optional
        Override of the analytic impact ratio (θ̇⁺ = η θ̇⁻) for single blocks;
        default Housner's 1 − 2mb²/I_O.
    interface_friction : float, optional
        Coulomb coefficient (≥ 0) of the block–block contacts of a stack; None
        (default): the same as ``friction``, which then holds for every contact.
    """

    friction: float = 1.0
    restitution: float = 0.0
    eta: float | None = None
    interface_friction: float | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "friction", _check(self.friction, "contact friction",
                                                    strict=False))
        object.__setattr__(self, "restitution", _check(self.restitution, "contact restitution",
                                                       strict=False, high=1.0))
        if self.eta is not None:
            object.__setattr__(self, "eta", _check(self.eta, "contact eta", strict=False,
                                                   high=1.0))
        if self.interface_friction is not None:
            object.__setattr__(self, "interface_friction", _check(
                self.interface_friction, "contact interface_friction", strict=False))

    @property
    def block_friction(self) -> float:
        """Coulomb coefficient between two blocks (``interface_friction`` or ``friction``)."""
        return self.friction if self.interface_friction is None else self.interface_friction

    def to_dict(self) -> dict[str, Any]:
        """Scenario-file representation."""
        d: dict[str, Any] = {"friction": self.friction, "restitution": self.restitution}
        if self.eta is not None:
            d["eta"] = self.eta
        if self.interface_friction is not None:
            d["interface_friction"] = self.interface_friction
        return d


@dataclass(frozen=True)
class Scenario:
    """A complete rocking problem: stack, contact, base motion, initial state, output.

    Parameters
    ----------
    name : str
        Identifier (catalog name or file stem).
    stack : Stack, Block or Assembly
        What rocks; a single Block is wrapped into a one-block Stack. An
        :class:`~rockbench.scenarios.assembly.Assembly` is any planar
        arrangement of blocks on the base and fixed supports (engines that
        build it declare ``Capabilities.assemblies``).
    contact : Contact
        Friction, restitution, optional analytic η.
    excitation : Excitation
        Base motion (default: none).
    initial_tilt : float
        Initial rotation as a fraction of the bottom block's λ; positive tilts
        toward +x. The whole stack is rotated rigidly about the bottom pivot and
        released from rest. Stacks only: an assembly's blocks have their own
        angles (0 here).
    duration : float
        Simulated time (s).
    output_rate : float
        Samples per second in the returned trajectories.
    g : float
        Gravity (m/s², acting along −z).
    description : str
        Free text (e.g. the paper case it reproduces).
    """

    name: str
    stack: Stack | Assembly
    contact: Contact = field(default_factory=Contact)
    excitation: Excitation = field(default_factory=Free)
    initial_tilt: float = 0.0
    duration: float = 10.0
    output_rate: float = 1000.0
    g: float = 9.81
    description: str = ""

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name.strip():
            raise ScenarioError("scenario name must be a non-empty string")
        if isinstance(self.stack, Block):
            object.__setattr__(self, "stack", Stack((self.stack,)))
        if not isinstance(self.stack, (Stack, Assembly)):
            raise ScenarioError("scenario stack must be a Stack, a Block or an Assembly")
        if not isinstance(self.contact, Contact):
            raise ScenarioError("scenario contact must be a Contact")
        if not isinstance(self.excitation, Excitation):
            raise ScenarioError("scenario excitation must be an Excitation")
        tilt = self.initial_tilt
        if not (checks.is_number(tilt) and math.isfinite(tilt) and abs(tilt) < 1.0):
            raise ScenarioError(
                f"initial tilt must be a fraction of λ with |tilt| < 1, got "
                f"{checks.describe(tilt)}"
            )
        if tilt != 0 and isinstance(self.stack, Assembly):
            raise ScenarioError(f"initial tilt is for stacks (got {tilt!r}); an assembly's "
                                f"blocks take their own angle")
        if not isinstance(self.description, str):
            raise ScenarioError(f"scenario description must be a string, got "
                                f"{checks.describe(self.description)}")
        object.__setattr__(self, "duration", _check(self.duration, "scenario duration",
                                                    unit="s"))
        object.__setattr__(self, "output_rate", _check(self.output_rate, "output_rate",
                                                       unit="samples/s"))
        object.__setattr__(self, "g", _check(self.g, "gravity", unit="m/s²"))
        if self.duration * self.output_rate < 1.0 - 1e-9:
            raise ScenarioError(
                f"output_rate {self.output_rate:g} samples/s gives a single sample over the "
                f"{self.duration:g} s run: a trajectory needs at least 2 (output_rate >= "
                f"1/duration = {1.0 / self.duration:.3g})")

    @property
    def blocks(self) -> tuple[Block, ...] | tuple[Block | Prism, ...]:
        """The blocks, bottom first (an assembly's in the order given)."""
        return self.stack.blocks

    @property
    def is_assembly(self) -> bool:
        """True when :attr:`stack` is an :class:`~rockbench.scenarios.assembly.Assembly`."""
        return isinstance(self.stack, Assembly)

    @property
    def block_angles(self) -> np.ndarray:
        """Each block's own orientation about +y at rest (rad), before :attr:`theta0`.

        Zeros for a stack; an assembly's block angles.
        """
        if isinstance(self.stack, Assembly):
            return self.stack.angles
        return np.zeros(len(self.stack.blocks))

    @property
    def n_blocks(self) -> int:
        """Number of blocks."""
        return len(self.stack.blocks)

    @property
    def critical_angle(self) -> float:
        """λ used to normalise results (smallest of the stack's critical angles)."""
        return self.stack.critical_angle(self.g)

    @property
    def theta0(self) -> float:
        """Initial rotation in rad (fraction × bottom block's λ); 0 for an assembly."""
        if isinstance(self.stack, Assembly):
            return 0.0
        return self.initial_tilt * self.blocks[0].rocking(self.g).lam

    @property
    def uplift_ratio(self) -> float:
        """Peak |ü_g| over the smallest static uplift threshold g·tan(λ)."""
        return self.excitation.peak_acceleration(self.duration) / (
            self.g * math.tan(self.critical_angle)
        )

    def output_times(self) -> np.ndarray:
        """Sample times 0, 1/rate, … up to the duration."""
        n = int(math.floor(self.duration * self.output_rate + 1e-9)) + 1
        return np.arange(n) / self.output_rate

    def initial_poses(self) -> tuple[np.ndarray, float]:
        """Centroid positions (x, z) of each block at t = 0 and the common angle θ0.

        The stack is rotated rigidly about the bottom pivot on the side it tilts to.
        Each block's orientation is θ0 plus its :attr:`block_angles` (an
        assembly's centroids at rest, θ0 = 0).
        """
        if isinstance(self.stack, Assembly):
            return self.stack.centroids, 0.0
        th = self.theta0
        c = self.stack.centroids
        if th == 0.0:
            return c.copy(), 0.0
        px = math.copysign(self.blocks[0].pivot_half_width, th) + self.stack.offsets[0]
        dx, dz = c[:, 0] - px, c[:, 1]
        # rotation about +y by θ maps (x, z) -> (x cos θ + z sin θ, −x sin θ + z cos θ)
        ct, st = math.cos(th), math.sin(th)
        return np.column_stack([px + dx * ct + dz * st, -dx * st + dz * ct]), th

    def replace(self, **changes: Any) -> Scenario:
        """A copy with some fields changed (validated again)."""
        kw = {f.name: getattr(self, f.name) for f in fields(self)}
        kw.update(changes)
        return Scenario(**kw)


# at the end: the assembly module builds on Block (defined above)
from rockbench.scenarios.assembly import Assembly, Prism  # noqa: E402
