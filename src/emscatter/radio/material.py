"""A Sionna RT radio material whose reflection, transmission and diffuse lobe come from
emscatter (importing this module imports Sionna RT and registers the class with Mitsuba as
``"emscatter-radio-material"``, so XML scenes can name it).

Per ray, at the scene frequency and the ray's incidence angle:

* **specular reflection / transmission** — the rough slab of :mod:`emscatter.radio.slab`,
  evaluated exactly per ray in Dr.Jit (Fresnel, slab phase, Kirchhoff factors) with the front
  face's coherent reflection ``r_coh`` = Fresnel + the interpolated roughness correction of
  :mod:`emscatter.radio.tables`. The time convention flips here (Sionna uses ``exp(+jωt)``):
  every complex quantity is the conjugate of emscatter's (:mod:`emscatter.radio.convention`).
* **diffuse reflection** — direction uniform on the hemisphere (both Sionna solvers reset the
  ray tube's solid angle to 2π after a diffuse bounce, so the lobe must not steer the
  direction); the Jones matrix carries ``√(lobe_qp · Ω)`` (``Ω`` the incident tube's solid angle,
  already divided by the event probability in the path solver, and divided here in
  ``sample``), in the local ``(h, v)`` bases of the incident and scattered planes, with the
  sign pattern of Sionna's own cross-polarization matrix. Co- and cross-polarized shares are
  emscatter's ``σ⁰_hh, σ⁰_vv`` and ``σ⁰_hv, σ⁰_vh``.
* **event probabilities** (``bs.pdf`` = the probability of the sampled event, as the solvers
  expect, not a direction density) are proportional to the coherent reflected, diffuse and
  transmitted powers (mean of the two polarizations), among the locally enabled events.
* **diffraction** uses Sionna's own UTD wedge coefficients with the flat slab of the medium
  (roughness does not enter the wedge).

**Diffuse transmission** (``transmission="diffuse"``, opt-in; isotropic rough slabs): the
tables of :mod:`emscatter.radio.transmission_tables` (from
:func:`emscatter.radio.slab_diffuse.diffuse_transmission`: faces from ``transmission_face``,
by default GO where it holds and otherwise SPM, PO or the IEM; radiative transport inside)
add a diffuse event into the back hemisphere (a ``DIFFUSE`` event, direction uniform on the back
hemisphere, Jones matrix ``√(T_p Ω / 2)`` into each scattered polarization: the light that
crossed the slab is unpolarized) and put the internal light that leaves through the front face
into the diffuse reflection lobe, so that ``R_coh + R_diff + T_coh + T_diff + A = 1`` per
incidence (within 1e-3, tests/test_radio_transmission_material.py). Both lobes sit in one
stacked texture: no extra lookup per ray. RadioMapSolver follows the event (it spawns the next
ray along the sampled direction, either side); Sionna's PathSolver connects diffuse events only
to receivers on the incident side (``sionna.rt`` ``sb_candidate_generator``) and cannot carry
it: there the material samples as with ``"coherent"`` (the internal light stays in its diffuse
reflection) and warns once
(:class:`~emscatter.radio.transmission_tables.DiffuseTransmissionWarning`). Off by default:
existing results and PathSolver users stay as they were, the model holds only where GO does
(outside it the material's ``out_of_range`` policy applies and the lobe is indicative), and the
tables cost a ``slab_diffuse`` build (~1–4 s per material and frequency). Flat materials ignore
it (the flat limit is Sionna's slab); half-spaces refuse it. The transmission events (option
checks, tables, PathSolver rule, event probabilities) live in
:mod:`emscatter.radio.material_transmission`.

**Anisotropic roughness** (walls with a texture direction, ``texture_direction=``): the
tables get the incidence-azimuth axis and the lobe lookup works in the texture frame of each hit
(:mod:`emscatter.radio.texture`, Dr.Jit side in :mod:`emscatter.radio.texture_jit`).

Tables are built lazily, the first time a solver traces the material at a frequency, and only
if some object of the scene uses it (Dr.Jit traces every live material, used or not). Changing
``scene.frequency`` checks the medium's band at once (an out-of-band ITU material fails even
if unused, as Sionna's own ITU materials do) and picks the cached table for that frequency on
the host. A material instance belongs to one scene (Sionna enforces it). Sionna attaches the
materials of an XML scene at its default 3.5 GHz, before you can set the frequency: a medium
whose band excludes 3.5 GHz (ITU floorboard, 50–100 GHz) cannot be named in XML — assign it from
Python after setting ``scene.frequency`` (:func:`emscatter.radio.scenes.load` does).

A rough wall so thick and lossy that one pass through it keeps less than 1e-6 of the field
(−120 dB; concrete at 140 GHz, 0.2 m) is treated as a half-space (no transmission, no back
face), which saves the slab arithmetic per ray; flat materials always keep Sionna's slab.
"""

from __future__ import annotations

import math

import drjit as dr
import mitsuba as mi
import numpy as np
from sionna.rt import RadioMaterial, RadioMaterialBase
from sionna.rt.constants import (
    DEFAULT_FREQUENCY,
    DEFAULT_THICKNESS,
    NO_JONES_MATRIX,
    InteractionType,
)
from sionna.rt.utils import (
    complex_sqrt,
    itu_coefficients_single_layer_slab,
    jones_matrix_to_world_implicit,
)

from .. import solvers
from .convention import sionna_permittivity
from .material_jones import specular_or_diffuse_matrix
from .material_slice import _parse_props, _Slice
from .material_transmission import (
    check_transmission,
    diffuse_tables,
    event_probabilities,
    through_on,
)
from .medium import check_thickness, resolve_medium
from .slab_faces import check_face
from .tables import TableOptions, build_tables, check_policy, check_surface
from .texture import build_textured_tables, check_direction, check_textured_surface
from .texture_jit import (
    TexturedSlice,
    folded_azimuth,
    opaque_float,
    tex_coord,
    texture_axes,
)

__all__ = ["EmscatterRadioMaterial", "PLUGIN_NAME"]

PLUGIN_NAME = "emscatter-radio-material"
_HALF_SPACE_DIFFRACTION_THICKNESS = 1e3  # [m] a half-space seen by Sionna's UTD wedge code


class EmscatterRadioMaterial(RadioMaterialBase):
    """A radio material from a rough surface and a medium (module docstring).

    Parameters
    ----------
    name : unique name in the scene (required unless loaded from XML).
    surface : 2-D roughness statistics (:mod:`emscatter.spectra`; anisotropic, ``length_y ≠
        length``, with ``texture_direction``), or ``None`` for a flat face — then the
        material is Sionna's own ``RadioMaterial`` with ``S = 0``.
    medium : ITU-R P.2040 name (``"concrete"``), a :class:`~emscatter.materials.Material`, or
        a permittivity (``exp(−iωt)``, ``Im ε ≥ 0``); or give ``eps_real`` [-] and
        ``conductivity`` [S/m] instead.
    thickness : slab thickness [m] (default 0.1 m, Sionna's default), or ``None`` for a
        half-space (no transmission).
    method : emscatter solver for the tables (``"auto"`` or a name); recorded per table.
    out_of_range : ``"warn"`` (default), ``"raise"`` or ``"ignore"`` when that solver is
        outside its validity range at the scene frequency.
    table_options : :class:`~emscatter.radio.tables.TableOptions` (grid sizes).
    texture_direction : world-frame direction of the surface's ``ℓx`` axis (three numbers),
        required for anisotropic roughness (``length_y ≠ length``), allowed for isotropic
        roughness (then the textured tables are used: a check of the textured path); projected
        onto each hit's tangent plane, with the degenerate rule of
        :mod:`emscatter.radio.texture` where it is parallel to the normal.
    transmission : ``"coherent"`` (default: the coherent slab only, as Sionna's own model) or
        ``"diffuse"`` (also the diffusely transmitted lobe of the rough slab; RadioMapSolver only,
        module docstring). Needs a slab (``thickness`` not ``None``) and no texture direction.
    transmission_face : the slab faces' model for ``transmission="diffuse"``, one of
        :data:`emscatter.radio.slab_faces.FACES` (default ``"auto"``: GO where it holds, else the
        first of SPM, PO, IEM valid from both sides; :func:`~emscatter.radio.slab_diffuse.
        diffuse_transmission`'s ``face=``).
    color : RGB in [0, 1] for Sionna's previews.
    """

    def __init__(
        self,
        name: str | None = None,
        surface=None,
        medium=None,
        *,
        eps_real: float | None = None,
        conductivity: float | None = None,
        thickness: float | None = DEFAULT_THICKNESS,
        method: str = "auto",
        out_of_range: str = "warn",
        table_options: TableOptions | None = None,
        texture_direction=None,
        transmission: str = "coherent",
        transmission_face: str = "auto",
        color=None,
        props: mi.Properties | None = None,
    ):
        if props is None:
            if not isinstance(name, str) or not name:
                raise ValueError("EmscatterRadioMaterial needs a name (a non-empty string)")
            props = mi.Properties(PLUGIN_NAME)
            props.set_id(name)
            if color is not None:
                props["color"] = mi.ScalarColor3f(*color)
        else:
            kw = _parse_props(props)
            surface = kw.get("surface")
            medium = kw.get("medium")
            eps_real = kw.get("eps_real")
            conductivity = kw.get("conductivity")
            thickness = kw.get("thickness", DEFAULT_THICKNESS)
            method = kw.get("method", "auto")
            texture_direction = kw.get("texture_direction")
            transmission = kw.get("transmission", "coherent")
            transmission_face = kw.get("transmission_face", "auto")
        super().__init__(props)
        self._medium = resolve_medium(medium, eps_real=eps_real, conductivity=conductivity)
        thickness = check_thickness(thickness)
        self._thickness = thickness
        self._texture = None
        if surface is None:
            if texture_direction is not None:
                raise ValueError(
                    f"texture_direction={texture_direction!r} given for a flat surface "
                    "(surface=None); a texture direction needs roughness"
                )
            self._surface = None
        elif texture_direction is not None:
            self._surface = check_textured_surface(surface)
            self._texture = check_direction(texture_direction)
            self._dir = mi.Vector3f(*(float(v) for v in self._texture))
            dr.make_opaque(self._dir)
        elif getattr(surface, "dimension", 2) == 2 and not getattr(surface, "is_isotropic", True):
            raise ValueError(
                "radio materials need isotropic 2-D roughness unless a texture direction is "
                f"given: anisotropic roughness ({surface.describe()}) needs texture_direction="
                "(dx, dy, dz), the world direction of the ℓx axis, e.g. (0, 0, 1) for vertical "
                "grooves"
            )
        else:
            self._surface = check_surface(surface)
        self._sigma = 0.0 if surface is None else float(surface.sigma)
        check_policy(out_of_range)
        if not isinstance(method, str) or (method != "auto" and method not in solvers.available()):
            raise ValueError(
                f"method must be 'auto' or one of {solvers.available()}, got {method!r}"
            )
        self._method = method
        self._transmission = check_transmission(transmission, thickness, self._texture)
        self._face = check_face(transmission_face)
        self._path_warned = False
        self._out_of_range = out_of_range
        self._options = table_options or TableOptions()
        self._tables: dict[float, _Slice] = {}
        self._active: _Slice | None = None
        self._frequency: float | None = None
        self._set_medium_constants(DEFAULT_FREQUENCY, check=False)
        # Attributes Sionna's UTD wedge code (RadioMaterial._diffraction_matrix) reads.
        self._d = mi.Float(
            thickness if thickness is not None else _HALF_SPACE_DIFFRACTION_THICKNESS
        )
        self._s = mi.Float(0.0)

    # ------------------------------------------------------------------ host side
    @RadioMaterialBase.scene.setter
    def scene(self, scene):
        RadioMaterialBase.scene.fset(self, scene)
        self.frequency_update()

    @property
    def medium(self):
        return self._medium

    @property
    def transmission(self) -> str:
        """``"coherent"`` (default) or ``"diffuse"`` (class docstring)."""
        return self._transmission

    @property
    def transmission_face(self) -> str:
        """The slab faces' model of the diffuse transmission (``transmission_face=``)."""
        return self._face

    @property
    def surface(self):
        return self._surface

    @property
    def thickness(self) -> float | None:
        return self._thickness

    @property
    def tables(self) -> dict:
        """Tables built so far, by frequency [Hz] (:class:`~emscatter.radio.tables.RadioTables`)."""
        return {f: s.tables for f, s in self._tables.items()}

    @property
    def active_tables(self):
        """Tables of the current scene frequency, or ``None`` until a solver needs them."""
        return None if self._active is None else self._active.tables

    @property
    def active_transmission_tables(self):
        """Diffuse-transmission tables of the current scene frequency
        (:class:`~emscatter.radio.transmission_tables.TransmissionTables`), or ``None``
        (``transmission="coherent"``, a flat or opaque wall, or not built yet)."""
        return None if self._active is None else getattr(self._active, "transmission", None)

    def _set_medium_constants(self, frequency: float, check: bool = True):
        try:
            eps = complex(np.asarray(self._medium.eps(frequency=frequency)))
        except ValueError as exc:
            if not check:
                eps = 1.0 + 0j
            else:
                raise type(exc)(f"radio material {self.name!r}: {exc}") from None
        self._eps = eps
        eta = complex(sionna_permittivity(eps))
        self._eta = mi.Complex2f(eta.real, eta.imag)
        dr.make_opaque(self._eta)
        k = 2.0 * math.pi * frequency / 299_792_458.0
        self._wavenumber = k
        self._k = opaque_float(k)
        self._lam = opaque_float(2.0 * math.pi / k)
        self._sig2 = opaque_float(self._sigma**2)
        d = self._thickness
        self._d_op = None if d is None else opaque_float(d)
        # A rough wall so thick and lossy that one pass through it leaves < 1e-6 of the field
        # (−120 dB) is a half-space: its back face and transmission are dropped (saves the
        # slab arithmetic per ray). Flat materials keep Sionna's slab exactly.
        one_pass = 0.0 if d is None else math.exp(-k * d * np.sqrt(eps + 0j).imag)
        self._opaque_wall = self._surface is not None and d is not None and one_pass < 1e-6

    def frequency_update(self):
        """Check the medium at the scene frequency (raises out of band) and select that
        frequency's tables on the host (built on first use)."""
        if self.scene is None:
            return
        f = float(self.scene.frequency[0])
        self._set_medium_constants(f)
        self._frequency = f
        self._active = self._tables.get(f)

    def _slice(self) -> _Slice | None:
        """The current tables, building them if a used material needs them (trace time)."""
        if self._surface is None:
            return None
        if self._active is not None:
            return self._active
        scene = self.scene
        if scene is None or not self.is_used or self._frequency is None:
            return self._dummy()
        build = build_tables if self._texture is None else build_textured_tables
        tables = build(
            self._surface,
            self._eps,
            self._frequency,
            method=self._method,
            out_of_range=self._out_of_range,
            label=self.name,
            options=self._options,
        )
        if self._texture is not None:
            self._active = self._tables[self._frequency] = TexturedSlice(tables)
            return self._active
        through = diffuse_tables(self, tables)
        self._active = self._tables[self._frequency] = _Slice(tables, through)
        return self._active

    def _dummy(self) -> _Slice:
        """Zero tables for a material no object uses (traced by Dr.Jit, never evaluated)."""
        if not hasattr(self, "_dummy_slice"):
            t = build_tables(
                None, 1.0 + 0j, DEFAULT_FREQUENCY, label=self.name, options=self._options
            )
            self._dummy_slice = _Slice(t)
            if self._texture is not None:
                t = build_textured_tables(
                    self._surface, 1.0 + 0j, DEFAULT_FREQUENCY, method=self._method,
                    out_of_range="ignore", label=self.name,
                    options=TableOptions(n_cos=4, n_cos_spm=4, n_theta=4, n_alpha=4, n_s=4,
                                         n_psi=2),
                )  # fmt: skip
                self._dummy_slice = TexturedSlice(t)
        return self._dummy_slice

    # ------------------------------------------------------------------ per ray (Dr.Jit)
    def _coefficients(self, cos_i, sl: _Slice | None, active, ki=None, tex=None):
        """Coherent ``(r_te, r_tm, t_te, t_tm)`` (Sionna convention) of the rough slab, the
        diffuse reflected share ``r_incoh,h + r_incoh,v`` (+ the internal ``R_int,h + R_int,v``
        with diffuse transmission) and the diffusely transmitted ``T_h + T_v`` at this
        incidence."""
        eta = self._eta
        zero_f = mi.Float(0.0)
        if sl is None:  # flat: exactly Sionna's ITU slab (or its half-space limit)
            if self._thickness is not None:
                return (
                    *itu_coefficients_single_layer_slab(cos_i, eta, self._d_op, self._lam),
                    zero_f,
                    zero_f,
                )
        sin2 = 1.0 - dr.square(cos_i)
        a = complex_sqrt(eta - sin2)
        r_te = (cos_i - a) * dr.rcp(cos_i + a)
        r_tm = (eta * cos_i - a) * dr.rcp(eta * cos_i + a)
        if sl is not None:
            if sl.n_psi:
                psi = folded_azimuth(ki, tex)[0] * (2.0 / math.pi)
                pos = mi.Point2f(tex_coord(cos_i, sl.n_cos), tex_coord(psi, sl.n_psi))
                v = sl.per_cos.eval(pos, active)
            else:
                v = sl.per_cos.eval(mi.Point1f(tex_coord(cos_i, sl.n_cos)), active)
            r1_te = r_te + mi.Complex2f(v[0], v[1])
            r1_tm = r_tm + mi.Complex2f(v[2], v[3])
            diffuse = dr.maximum(v[4] + v[5], 0.0)
            through = zero_f
            if sl.n_psi == 0 and sl.stacked:
                diffuse = diffuse + dr.maximum(v[7], 0.0)
                through = dr.maximum(v[6], 0.0)
        else:
            r1_te, r1_tm, diffuse, through = r_te, r_tm, zero_f, zero_f
        zero = mi.Complex2f(0.0, 0.0)
        if self._thickness is None or self._opaque_wall:
            return r1_te, r1_tm, zero, zero, diffuse, through
        k = self._k
        k2z = k * a
        q_t = k * cos_i - k2z
        chi_t = self._mean_field(-0.5 * self._sig2 * (q_t * q_t))
        chi_i = self._mean_field(-2.0 * self._sig2 * (k2z * k2z))
        ph = dr.exp(mi.Complex2f(0.0, -1.0) * (k * self._d_op) * a)
        ph2 = ph * ph
        out = []
        for r0, r1 in ((r_te, r1_te), (r_tm, r1_tm)):
            r_in = -r0 * chi_i
            inv = dr.rcp(1.0 - r_in * r_in * ph2)
            tt = (1.0 - r0 * r0) * chi_t * chi_t
            out.append((r1 + tt * r_in * ph2 * inv, tt * ph * inv))
        return out[0][0], out[1][0], out[0][1], out[1][1], diffuse, through

    @staticmethod
    def _mean_field(expo):
        """``exp(expo)`` with ``Re(expo)`` clipped at 0 (a passive mean field cannot grow)."""
        return dr.exp(mi.Complex2f(dr.minimum(dr.real(expo), 0.0), dr.imag(expo)))

    def _context(self, si):
        ki = si.wi
        cos_i = dr.clip(-ki.z, 0.0, 1.0)
        to_world = mi.Matrix3f(si.sh_frame.s, si.sh_frame.t, si.sh_frame.n).T
        tex = None if self._texture is None else texture_axes(self._dir, si)
        return ki, cos_i, to_world, tex

    def _jones(
        self, si, to_world, ki, coefs, sl, events, ko_diff, ko_diffr, diffraction_on, active,
        tex=None,
    ):  # fmt: skip
        """Jones matrix (world implicit frame) of the event of each lane: specular reflection or
        transmission, diffuse reflection into ``ko_diff``, diffraction into ``ko_diffr``."""
        r_te, r_tm, t_te, t_tm, _, _ = coefs
        reflection, diffuse, diffraction = events
        ko_spec = dr.select(reflection, mi.reflect(-ki), ki)
        c_te = dr.select(reflection, r_te, t_te)
        c_tm = dr.select(reflection, r_tm, t_tm)
        if sl is None:  # flat: exactly Sionna's specular matrix
            jones = jones_matrix_to_world_implicit(c_te, c_tm, to_world, ki, ko_spec)
        else:
            jones = specular_or_diffuse_matrix(
                to_world, ki, ko_spec, c_te, c_tm, sl, diffuse, ko_diff, si.t, active, tex
            )
        if diffraction_on:
            jf = RadioMaterial._diffraction_matrix(
                self, to_world, ki, ko_diffr, si, self._eta, self._k
            )
            jones = dr.select(diffraction, jf, jones)
        return jones

    def sample(self, ctx, si, sample1, sample2, active=True):
        sl = self._slice()
        ki, cos_i, to_world, tex = self._context(si)
        diffraction_on = (ctx.component & InteractionType.DIFFRACTION) > 0
        enabled = dr.reinterpret_array(mi.UInt, si.dp_du.z)
        diffraction = mi.Bool(active) & (enabled == InteractionType.DIFFRACTION)
        coefs = self._coefficients(cos_i, sl, active, ki, tex)
        prs, prd, pt, pdt, none = event_probabilities(coefs, enabled, through_on(self, sl, ctx))
        specular = sample1 < prs
        diffuse = (sample1 >= prs) & (sample1 < prs + prd)
        through = (sample1 >= prs + prd) & (sample1 < prs + prd + pdt)
        transmission = ~specular & ~diffuse & ~through
        diffuse |= through
        event = dr.select(
            specular, mi.UInt(InteractionType.SPECULAR), mi.UInt(InteractionType.DIFFUSE)
        )
        event = dr.select(transmission, mi.UInt(InteractionType.REFRACTION), event)
        event = dr.select(none, mi.UInt(InteractionType.NONE), event)
        event = dr.select(diffraction, mi.UInt(InteractionType.DIFFRACTION), event)
        prob = dr.select(specular, prs, dr.select(through, pdt, dr.select(diffuse, prd, pt)))
        prob = dr.select(diffraction, 1.0, prob)
        diffuse &= ~diffraction & ~none
        reflection = specular | diffuse
        ko_diff = mi.warp.square_to_uniform_hemisphere(sample2)
        ko_diff.z = dr.select(through, -dr.abs(ko_diff.z), dr.abs(ko_diff.z))
        ko = dr.select(diffuse, ko_diff, dr.select(reflection, mi.reflect(-ki), ki))
        ko_diffr = ko
        if diffraction_on:
            ko_diffr = RadioMaterial._diffraction_direction(self, si, sample2.x, ki)
            ko = dr.select(diffraction, ko_diffr, ko)
        if (ctx.component & NO_JONES_MATRIX) == 0:
            events = (reflection, diffuse, diffraction)
            jones = self._jones(
                si, to_world, ki, coefs, sl, events, ko_diff, ko_diffr, diffraction_on, active,
                tex,
            )  # fmt: skip
            # the sampled event is weighted by 1/√p (Sionna's convention for sample())
            jones *= dr.detach(dr.select(prob > 0.0, dr.rsqrt(prob), 0.0))
            jones = mi.Spectrum(jones)
        else:
            jones = mi.Spectrum(0.0)
        bs = mi.BSDFSample3f()
        bs.sampled_component = event
        bs.wo = si.to_world(ko)
        bs.pdf = prob
        bs.sampled_type = mi.UInt32(+mi.BSDFFlags.DeltaReflection)
        bs.eta = 1.0
        return bs, jones

    def eval(self, ctx, si, wo, active=True):
        sl = self._slice()
        ki, cos_i, to_world, tex = self._context(si)
        event = dr.reinterpret_array(mi.UInt, si.dp_du.z)
        diffuse = event == InteractionType.DIFFUSE
        reflection = (event == InteractionType.SPECULAR) | diffuse
        diffraction = event == InteractionType.DIFFRACTION
        ko = si.to_local(wo)
        coefs = self._coefficients(cos_i, sl, active, ki, tex)
        diffraction_on = (ctx.component & InteractionType.DIFFRACTION) > 0
        events = (reflection, diffuse, diffraction)
        jones = self._jones(
            si, to_world, ki, coefs, sl, events, ko, ko, diffraction_on, active, tex
        )
        return mi.Spectrum(jones)

    def pdf(self, ctx, si, wo, active=True):
        """Probability of the event stored in ``si.dp_du.z`` with all reflection and
        transmission events enabled (the solvers read ``bs.pdf`` from :meth:`sample`)."""
        sl = self._slice()
        ki, cos_i, _, tex = self._context(si)
        event = dr.reinterpret_array(mi.UInt, si.dp_du.z)
        every = InteractionType.SPECULAR | InteractionType.DIFFUSE | InteractionType.REFRACTION
        prs, prd, pt, pdt, _ = event_probabilities(
            self._coefficients(cos_i, sl, active, ki, tex), mi.UInt(every), through_on(self, sl)
        )
        p = dr.select(event == InteractionType.SPECULAR, prs, prd)
        p = dr.select((event == InteractionType.DIFFUSE) & (si.to_local(wo).z < 0.0), pdt, p)
        p = dr.select(event == InteractionType.REFRACTION, pt, p)
        return dr.select(event == InteractionType.DIFFRACTION, 1.0, p)

    def traverse(self, callback):
        """Nothing differentiable: the tables come from emscatter on the host."""

    def to_string(self) -> str:
        surf = "flat" if self._surface is None else self._surface.describe()
        d = "half-space" if self._thickness is None else f"thickness {self._thickness:g} m"
        t = self.active_tables
        tab = "tables not built yet" if t is None else t.describe()
        tt = self.active_transmission_tables
        if tt is not None:
            tab += "; " + tt.describe()
        return (
            f"EmscatterRadioMaterial {self.name!r}: {self._medium.describe()}; {surf}; {d}; {tab}"
        )


mi.register_bsdf(PLUGIN_NAME, lambda props: EmscatterRadioMaterial(props=props))
