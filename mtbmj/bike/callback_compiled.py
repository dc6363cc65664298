"""Compiled bike callback: ``mtbmj.bike.callback.BikeCallback`` (fork, shock through the leverage
curve, both radial tires with their patch search, the rider's drive, its legs and arms) as native
code that MuJoCo calls every evaluation.

``BikeCallback`` (Python) stays the specification and the fallback; this module evaluates the same
arithmetic in the same order on the same schedule (each tire's contact patches searched afresh
every ``refresh`` s of simulated time or 0.25 mm of axle travel, kept while the axle stays on the
straight stretch its single patch lies on), so the two agree to round-off.

Design (the rolling front end's, ``mtbmj.rolling.callback_compiled``):

* The fork and the shock laws are flattened by ``controllers.lawcodes.flatten`` and evaluated by
  the compiled kernels (``controllers.kernels.fork_force``, or ``fork_force_rate`` with a
  friction state); the tire and the rim
  by ``controllers.kernels.rolling_tire_force`` / ``rim_force``; the drive by
  ``controllers.drive.drive_force`` and ``eased`` compiled (``controllers.jit.law_function``); the leverage
  curve's lookups (``mtbmj.bike.spec.leverage_ratio`` / ``leverage_stroke``) are those plain
  functions compiled. Nothing of them is written here.
* The patch search is the front end's compiled one (``update_patches``: ``PatchSearch``, with its
  straight stretches), each wheel with a row in the front end's slot layout (terrain, stretches,
  radius, margin, piece, patches).
* One numba ``cfunc`` serves every ``CompiledBikeCallback`` through a registry of its own
  (``controllers.native_data.Registry``) and leaves every other model alone.
* ``mjData`` is read through byte offsets: the front end's fields from
  ``controllers.native_data.mjdata_layout``, and the kinematics the Python callback reads from
  MuJoCo (``xpos``, ``xmat``, ``xipos``, ``site_xpos``, ``cvel``, ``subtree_com``), and
  ``xfrc_applied`` (where the tire and drive forces go, at the wheels' centres), ``xanchor``,
  ``xaxis`` and ``qfrc_applied`` (the rider's legs and arms on its joints), at their places
  among ``mjData``'s pointer fields (``mujoco.introspect``'s field order), each checked against the
  live arrays of a model before first use. The axle velocities are ``mj_objectVelocity``'s
  arithmetic on ``cvel`` (the site's linear velocity, world axes), the centre of mass's horizontal
  momentum the bike_x row of ``mj_mulM`` written as the sum over the bodies of m (v + w x c).

Limits: at most ``MAX_PATCHES`` patches per tire (beyond that the slot raises its overflow flag and
``mtbmj.bike.run.simulate`` reruns on the Python path); a terrain or tire subclass, or a law with no
compiled form, runs on the Python path. One ``mjData`` at a time per model, as ``BikeCallback``.
"""
from __future__ import annotations

import ctypes
import math
import threading
import time
import weakref

import numpy as np

from mtbmj.controllers.compiled import unavailable_reason, warn_once
from mtbmj.controllers.drive import LIFT_EASE_DEG
from mtbmj.controllers.jit import FALLBACK_MESSAGE, callback, kernel, law_function, numba as _numba
from mtbmj.controllers.lawcodes import FLOAT_WIDTH as LAW_FLOAT_WIDTH, INT_WIDTH as LAW_INT_WIDTH
from mtbmj.controllers.lawcodes import UnsupportedLaw, flatten
from mtbmj.controllers.native_data import Registry, mjdata_layout, verify
from mtbmj.controllers.stops import STIFFENING_M
from mtbmj.rolling import callback_compiled as rolling
from mtbmj.rolling.callback_compiled import MAX_PATCHES, UnsupportedRolling
from mtbmj.runpath.callbacks import CompiledShell

SLOTS = 64
KINEMATICS = ("xpos", "xmat", "xipos", "site_xpos", "cvel", "subtree_com", "xfrc_applied", "xanchor", "xaxis",
              "qfrc_applied")
WI, WF = rolling.INT_WIDTH, rolling.FLOAT_WIDTH  # a wheel's row in the front end's slot layout

# integer row of a slot
(R_MODEL, R_FQ, R_FV, R_SV, R_A_FORK, R_A_SHOCK, R_A_FS, R_A_SS, R_ACT_F, R_ACT_S, R_A_TX0, R_A_TZ0, R_A_TX1,
 R_A_TZ1, R_A_DX, R_A_DZ, R_A_PROBE0, R_A_PROBE1, R_A_SHOCK_PROBE, R_SITE0, R_SITE1, R_SBODY0, R_SBODY1, R_FRAME,
 R_ROOT0, R_ROOT1, R_NBODY, R_MASS, R_FORK_STATE, R_SHOCK_STATE, R_DRIVE, R_NL, R_LW, R_LR, R_LS, R_CALLS,
 R_REFRESHES, R_BODYROOT, R_WHEEL0, R_WHEEL1, R_LIMB_F0, R_LIMB_R0, R_LIMB_F1, R_LIMB_R1, R_JZ, R_JP, R_VZ,
 R_VP, R_REACT0, R_REACT1, R_A_GFX, R_A_GFZ, R_A_CF, R_A_CR, R_XQ, R_RIDER, R_CALIPER, R_ARM_JOINT, R_PITCHQ) = range(59)
INT_WIDTH = R_PITCHQ + 1  # one row per name above: the width follows the list
DRIVE_PEDAL = 2  # R_DRIVE: 0 coasting, 1 the rider's speed controller, 2 pedalling (controllers.drive.pedal_forces)
# float row of a slot
(F_SPEED, F_TRACTION, F_REFRESH, F_TOTAL_MASS, F_PIVOT_X, F_REAR_Z0, F_NEXT0, F_NEXT1, F_LAST0, F_LAST1,
 F_REFRESH_DISTANCE, F_DRIVE_KV, F_DRIVE_PUSH, F_DRIVE_POWER, F_DRIVE_BRAKE, F_LIMB_K0, F_LIMB_C0, F_LIMB_REST0,
 F_LIMB_K1, F_LIMB_C1, F_LIMB_REST1, F_RADIUS, F_CHAIN_RING, F_CHAIN_COG, F_LIFT_LO, F_LIFT_HI) = range(26)
FLOAT_WIDTH = F_LIFT_HI + 1

REGISTRY = Registry("mtbmj_bike_registry_v10", SLOTS,
                    {"ints": (INT_WIDTH, np.int64), "floats": (FLOAT_WIDTH, np.float64),
                     "wheel_ints": (2 * WI, np.int64), "wheel_floats": (2 * WF, np.float64),
                     "fork_ints": (LAW_INT_WIDTH, np.int64), "fork_floats": (LAW_FLOAT_WIDTH, np.float64),
                     "shock_ints": (LAW_INT_WIDTH, np.int64), "shock_floats": (LAW_FLOAT_WIDTH, np.float64)},
                    ("qpos", "qvel", "act", "ctrl", "time") + KINEMATICS)
(M_USED, M_INTS, M_FLOATS, M_WINTS, M_WFLOATS, M_FINTS, M_FFLOATS, M_SINTS, M_SFLOATS, M_QPOS, M_QVEL, M_ACT,
 M_CTRL, M_TIME, M_XPOS, M_XMAT, M_XIPOS, M_SITE_XPOS, M_CVEL, M_SUBTREE_COM, M_XFRC, M_XANCHOR, M_XAXIS,
 M_QFRC) = (
    REGISTRY.index[name] for name in ("used", "ints", "floats", "wheel_ints", "wheel_floats", "fork_ints",
                                      "fork_floats", "shock_ints", "shock_floats", "qpos", "qvel", "act", "ctrl",
                                      "time") + KINEMATICS)
_INTS, _FLOATS = REGISTRY.tables["ints"], REGISTRY.tables["floats"]
_WINTS, _WFLOATS = REGISTRY.tables["wheel_ints"], REGISTRY.tables["wheel_floats"]


def kinematics_layout(model) -> dict:
    """Byte offsets in ``mjData`` of ``KINEMATICS``: mjData's fields from ``qpos`` on are pointers,
    8 bytes each, in ``mujoco.introspect``'s order (checked), ``qpos`` where ``mjdata_layout`` puts it;
    each offset checked against a live ``MjData`` of ``model`` (the pointer there is the numpy
    array's address). Raises RuntimeError when either check fails."""
    import mujoco
    from mujoco.introspect import ast_nodes, structs

    fields = structs.STRUCTS["mjData"].fields
    names = [getattr(f, "name", None) for f in fields]
    first = names.index("qpos")
    base = mjdata_layout()["qpos"]
    data = mujoco.MjData(model)
    out = {}
    for name in KINEMATICS:
        k = names.index(name)
        if not all(isinstance(f.type, ast_nodes.PointerType) for f in fields[first:k + 1]):
            raise RuntimeError(f"mjData layout: a field between qpos and {name} is not a pointer")
        offset = base + 8 * (k - first)
        array = getattr(data, name)
        if array.size and ctypes.c_void_p.from_address(data._address + offset).value != array.ctypes.data:
            raise RuntimeError(f"mjData layout check failed: {name!r} is not at byte {offset}")
        out[name] = offset
    return out


COMPILE_SECONDS: float | None = None
if _numba is not None:
    from mtbmj.bike import spec as _spec
    from mtbmj.controllers import drive as _drive
    from mtbmj.controllers import kernels as _kernels
    from mtbmj.controllers.native_data import address_of as _address_of, f64_pointer as _f64_pointer
    from mtbmj.controllers.native_data import find_slot as _find_slot
    from mtbmj.controllers.native_data import i64_pointer as _i64_pointer, pointer_field as _pointer_field
    from numba import types as _t

    _compile_start = time.perf_counter()
    _registry = REGISTRY.reader()
    _fork_force, _fork_force_rate = _kernels.fork_force, _kernels.fork_force_rate
    _tire_force, _rim_force = _kernels.rolling_tire_force, _kernels.rim_force
    _drive_force = law_function(_drive.drive_force)
    _eased = law_function(_drive.eased)
    law_function(_drive.at_patch)
    _wheel_forces = law_function(_drive.wheel_forces)
    _chain_pull = law_function(_drive.chain_pull)
    law_function(_drive.pedal_forces)
    law_function(_drive.pedal_peak)
    _pedal_drive = law_function(_drive.pedal_drive)
    law_function(_spec.stroke_piece)
    _leverage_ratio = law_function(_spec.leverage_ratio)
    _leverage_stroke = law_function(_spec.leverage_stroke)
    _update_patches, piece_index = rolling.update_patches, rolling.piece_index
    (_R_NPATCH, _F_RADIUS, _F_RATE, _F_DAMPING, _F_MARGIN, _F_RIM_D, _F_RIM_K, _F_RIM_C, _F_PATCHES,
     _PATCH_WIDTH) = (
        rolling.R_NPATCH, rolling.F_RADIUS, rolling.F_RATE, rolling.F_DAMPING, rolling.F_MARGIN, rolling.F_RIM_D,
        rolling.F_RIM_K, rolling.F_RIM_C, rolling.F_PATCHES, rolling.PATCH_WIDTH)

    @kernel
    def site_velocity(cvel, subtree_com, site_xpos, body, root, site):
        """(vx, vz) of mj_objectVelocity(site, world axes): cvel's linear part moved from the
        root's centre of mass to the site (lin - (site - com) x w)."""
        c = 6 * body
        r = 3 * root
        s = 3 * site
        dx = site_xpos[s] - subtree_com[r]
        dy = site_xpos[s + 1] - subtree_com[r + 1]
        dz = site_xpos[s + 2] - subtree_com[r + 2]
        wx, wy, wz = cvel[c], cvel[c + 1], cvel[c + 2]
        return cvel[c + 3] - (dy * wz - dz * wy), cvel[c + 5] - (dx * wy - dy * wx)

    @kernel
    def momentum_x(cvel, subtree_com, xipos, mass, roots, nbody):
        """The bike_x row of mj_mulM(qvel): sum over the bodies of m (v - (c - com) x w), x."""
        p = 0.0
        for b in range(1, nbody):
            c = 6 * b
            r = 3 * roots[b]
            dy = xipos[3 * b + 1] - subtree_com[r + 1]
            dz = xipos[3 * b + 2] - subtree_com[r + 2]
            p += mass[b] * (cvel[c + 3] - (dy * cvel[c + 2] - dz * cvel[c + 1]))
        return p

    @kernel
    def limb(site_xpos, xaxis, xanchor, I, F, k, vz, vp):
        """(f dL/dz, f dL/dth) of limb k on the rider's joints: BikeCallback.limb_forces."""
        p = 3 * I[R_LIMB_R0 + 2 * k]
        q = 3 * I[R_LIMB_F0 + 2 * k]
        dx = site_xpos[p] - site_xpos[q]
        dy = site_xpos[p + 1] - site_xpos[q + 1]
        dz = site_xpos[p + 2] - site_xpos[q + 2]
        length = math.sqrt(dx * dx + dy * dy + dz * dz)
        ux = dx / length
        uy = dy / length
        uz = dz / length
        a = 3 * I[R_JZ]
        h = 3 * I[R_JP]
        rx = site_xpos[p] - xanchor[h]
        ry = site_xpos[p + 1] - xanchor[h + 1]
        rz = site_xpos[p + 2] - xanchor[h + 2]
        d_slide = ux * xaxis[a] + uy * xaxis[a + 1] + uz * xaxis[a + 2]
        d_hinge = (ux * (xaxis[h + 1] * rz - xaxis[h + 2] * ry) + uy * (xaxis[h + 2] * rx - xaxis[h] * rz)
                   + uz * (xaxis[h] * ry - xaxis[h + 1] * rx))
        o = 3 * k
        f = -F[F_LIMB_K0 + o] * (length - F[F_LIMB_REST0 + o]) - F[F_LIMB_C0 + o] * (d_slide * vz + d_hinge * vp)
        return f * d_slide, f * d_hinge

    @kernel
    def tire_on_patches(WI_, WF_, cx, cz, vx, vz):
        """RadialTire.force on the wheel row's patches (each its share of the law): (fx, fz, deepest
        deflection)."""
        r = WF_[_F_RADIUS]
        k = WF_[_F_RATE]
        b = WF_[_F_DAMPING]
        fx = 0.0
        fz = 0.0
        deepest = -math.inf
        for p in range(WI_[_R_NPATCH]):
            o = _F_PATCHES + _PATCH_WIDTH * p
            qx, qz, nx, nz, sx, sz = WF_[o], WF_[o + 1], WF_[o + 2], WF_[o + 3], WF_[o + 4], WF_[o + 5]
            d = r - ((cx - qx) * nx + (cz - qz) * nz)
            rate = -((vx - sx) * nx + (vz - sz) * nz)
            if d > deepest:
                deepest = d
            if d > 0.0:
                f = max(0.0, _tire_force(k, b, d, rate))
                if WF_[_F_RIM_K] > 0.0:  # the rim strikes (Rim.force)
                    f += _rim_force(WF_[_F_RIM_D], WF_[_F_RIM_K], WF_[_F_RIM_C], d, rate)
                f *= WF_[o + 6]  # its share (RadialTire.force)
                if f > 0.0:
                    fx += f * nx
                    fz += f * nz
        if deepest == -math.inf:
            deepest = r - WF_[_F_RADIUS] - WF_[_F_MARGIN]
        return fx, fz, deepest

    @callback(_t.void(_t.voidptr, _t.voidptr))
    def _dispatch(m, d):
        slot = _find_slot(_registry(M_INTS), _registry(M_USED), INT_WIDTH, _address_of(m))
        if slot < 0:
            return  # not one of ours: leave the model alone
        I = _numba.carray(_i64_pointer(_registry(M_INTS) + 8 * INT_WIDTH * slot), (INT_WIDTH,))
        F = _numba.carray(_f64_pointer(_registry(M_FLOATS) + 8 * FLOAT_WIDTH * slot), (FLOAT_WIDTH,))
        W_I = _numba.carray(_i64_pointer(_registry(M_WINTS) + 8 * 2 * WI * slot), (2 * WI,))
        W_F = _numba.carray(_f64_pointer(_registry(M_WFLOATS) + 8 * 2 * WF * slot), (2 * WF,))
        FI = _numba.carray(_i64_pointer(_registry(M_FINTS) + 8 * LAW_INT_WIDTH * slot), (LAW_INT_WIDTH,))
        FP = _numba.carray(_f64_pointer(_registry(M_FFLOATS) + 8 * LAW_FLOAT_WIDTH * slot), (LAW_FLOAT_WIDTH,))
        SI = _numba.carray(_i64_pointer(_registry(M_SINTS) + 8 * LAW_INT_WIDTH * slot), (LAW_INT_WIDTH,))
        SP = _numba.carray(_f64_pointer(_registry(M_SFLOATS) + 8 * LAW_FLOAT_WIDTH * slot), (LAW_FLOAT_WIDTH,))
        I[R_CALLS] += 1
        qpos = _pointer_field(d, _registry(M_QPOS))
        qvel = _pointer_field(d, _registry(M_QVEL))
        act = _pointer_field(d, _registry(M_ACT))
        ctrl = _pointer_field(d, _registry(M_CTRL))
        xpos = _pointer_field(d, _registry(M_XPOS))
        xmat = _pointer_field(d, _registry(M_XMAT))
        xipos = _pointer_field(d, _registry(M_XIPOS))
        site_xpos = _pointer_field(d, _registry(M_SITE_XPOS))
        cvel = _pointer_field(d, _registry(M_CVEL))
        subtree_com = _pointer_field(d, _registry(M_SUBTREE_COM))
        xfrc = _pointer_field(d, _registry(M_XFRC))
        t = _f64_pointer(_address_of(d) + _registry(M_TIME))[0]
        # the rider's legs and arms, on its two joints (BikeCallback.limb_forces)
        xanchor = _pointer_field(d, _registry(M_XANCHOR))
        xaxis = _pointer_field(d, _registry(M_XAXIS))
        qfrc = _pointer_field(d, _registry(M_QFRC))
        vz = qvel[I[R_VZ]]
        vp = qvel[I[R_VP]]
        qz0, qp0 = limb(site_xpos, xaxis, xanchor, I, F, 0, vz, vp)
        qz1, qp1 = limb(site_xpos, xaxis, xanchor, I, F, 1, vz, vp)
        qfrc[I[R_VZ]] = 0.0 + qz0 + qz1
        qfrc[I[R_VP]] = 0.0 + qp0 + qp1
        # the fork
        x = qpos[I[R_FQ]]
        v = qvel[I[R_FV]]
        if I[R_FORK_STATE]:  # force and state rate at once (a stick state's rate worked out once)
            force, rate = _fork_force_rate(FI, FP, x, v, act[I[R_ACT_F]])
            ctrl[I[R_A_FORK]] = -force
            ctrl[I[R_A_FS]] = rate
        else:
            ctrl[I[R_A_FORK]] = -_fork_force(FI, FP, x, v, 0.0)
        # the shock: (w, dw/dphi) from the rear axle in the frame's coordinates (BikeCallback.shock_state)
        fr = I[R_FRAME]
        ra = 3 * I[R_SITE1]
        r0 = site_xpos[ra] - xpos[3 * fr]
        r1 = site_xpos[ra + 1] - xpos[3 * fr + 1]
        r2 = site_xpos[ra + 2] - xpos[3 * fr + 2]
        o = 9 * fr
        local0 = xmat[o] * r0 + xmat[o + 3] * r1 + xmat[o + 6] * r2
        local2 = xmat[o + 2] * r0 + xmat[o + 5] * r1 + xmat[o + 8] * r2
        w = local2 - F[F_REAR_Z0]
        dw = -(local0 - F[F_PIVOT_X])
        nl = I[R_NL]
        LW = _numba.carray(_f64_pointer(I[R_LW]), (nl,))
        LR = _numba.carray(_f64_pointer(I[R_LR]), (nl,))
        LS = _numba.carray(_f64_pointer(I[R_LS]), (nl,))
        i = piece_index(LW, nl, w)
        ds = dw / _leverage_ratio(LW, LR, i, w)
        s = _leverage_stroke(LW, LR, LS, i, w)
        sd = ds * qvel[I[R_SV]]
        if I[R_SHOCK_STATE]:
            fs, rate = _fork_force_rate(SI, SP, s, sd, act[I[R_ACT_S]])
            ctrl[I[R_A_SS]] = rate
        else:
            fs = _fork_force(SI, SP, s, sd, 0.0)
        ctrl[I[R_A_SHOCK]] = -fs * ds
        ctrl[I[R_A_SHOCK_PROBE]] = fs
        # the tires
        fx = 0.0
        fz = 0.0
        fxf = 0.0
        fzf = 0.0
        df = 0.0
        deflection = 0.0
        for k in range(2):
            wi = W_I[k * WI:(k + 1) * WI]
            wf = W_F[k * WF:(k + 1) * WF]
            site = I[R_SITE0 + k]
            cx = site_xpos[3 * site]
            cz = site_xpos[3 * site + 2]
            vx, vz = site_velocity(cvel, subtree_com, site_xpos, I[R_SBODY0 + k], I[R_ROOT0 + k], site)
            if t >= F[F_NEXT0 + k] or abs(cx - F[F_LAST0 + k]) > F[F_REFRESH_DISTANCE]:
                # the front end's search (PatchSearch): kept while the axle stays over a straight stretch
                if _update_patches(wi, wf, cx, cz, t):
                    I[R_REFRESHES] += 1
                F[F_NEXT0 + k] = t + F[F_REFRESH] - 1e-12
                F[F_LAST0 + k] = cx
            fx, fz, deflection = tire_on_patches(wi, wf, cx, cz, vx, vz)
            ctrl[I[R_A_TX0 + 2 * k]] = fx
            ctrl[I[R_A_TZ0 + 2 * k]] = fz
            ctrl[I[R_A_PROBE0 + k]] = deflection
            if k == 0:
                fxf = fx
                fzf = fz
                df = deflection
        # the drive and the brakes: the ground's forces at the contact patches, each a force at its
        # axle and a couple on the part reacting it (BikeCallback; controllers.drive.wheel_forces)
        dxf = 0.0
        dzf = 0.0
        tf = 0.0
        dxr = 0.0
        dzr = 0.0
        tr = 0.0
        foot_x = 0.0
        foot_z = 0.0
        foot_px = 0.0
        foot_pz = 0.0
        vcom = 0.0
        if I[R_DRIVE] != 0:  # the centre of mass's speed, as the rider's speed loop and its pedalling read it
            nb = I[R_NBODY]
            mass = _numba.carray(_f64_pointer(I[R_MASS]), (nb,))
            roots = _numba.carray(_i64_pointer(I[R_BODYROOT]), (nb,))
            vcom = momentum_x(cvel, subtree_com, xipos, mass, roots, nb) / F[F_TOTAL_MASS]
        if I[R_DRIVE] == DRIVE_PEDAL:  # the crank's torque pulls the chain (controllers.drive.pedal_drive)
            dxf, dzf, tf, dxr, dzr, tr, foot_x, foot_z, foot_px, foot_pz = _pedal_drive(
                qpos[I[R_XQ]], vcom, F[F_DRIVE_POWER], F[F_CHAIN_RING], F[F_CHAIN_COG], F[F_RADIUS], fxf, fzf, df,
                fx, fz, deflection, F[F_TRACTION])
        elif I[R_DRIVE] != 0 and math.hypot(fxf, fzf) + math.hypot(fx, fz) > 0.0:
            f = _drive_force(F[F_SPEED], vcom, F[F_DRIVE_KV], F[F_DRIVE_PUSH], F[F_DRIVE_POWER], F[F_DRIVE_BRAKE])
            f = _eased(f, qpos[I[R_PITCHQ]], math.hypot(fxf, fzf) > 0.0, F[F_LIFT_LO], F[F_LIFT_HI])
            dxf, dzf, tf, dxr, dzr, tr = _wheel_forces(f, fxf, fzf, df, fx, fz, deflection, F[F_TRACTION],
                                                       F[F_RADIUS])
        ctrl[I[R_A_DX]] = dxr  # the rear tyre's ground force; the front's and the couples recorded beside
        ctrl[I[R_A_DZ]] = dzr
        ctrl[I[R_A_GFX]] = dxf
        ctrl[I[R_A_GFZ]] = dzf
        ctrl[I[R_A_CF]] = tf
        ctrl[I[R_A_CR]] = tr
        o = 6 * I[R_WHEEL0]
        xfrc[o] = fxf + dxf
        xfrc[o + 1] = 0.0
        xfrc[o + 2] = fzf + dzf
        o = 6 * I[R_WHEEL1]
        xfrc[o] = fx + dxr
        xfrc[o + 1] = 0.0
        xfrc[o + 2] = fz + dzr
        o = 6 * I[R_REACT0]
        xfrc[o + 3] = 0.0
        xfrc[o + 4] = tf
        xfrc[o + 5] = 0.0
        if F[F_CHAIN_COG] > 0.0:  # the chain makes the rear couple (BikeCallback; controllers.drive.chain_pull)
            fr = I[R_FRAME]
            m9 = 9 * fr
            r0 = site_xpos[3 * I[R_SITE1]] - xpos[3 * fr]
            r1 = site_xpos[3 * I[R_SITE1] + 1] - xpos[3 * fr + 1]
            r2 = site_xpos[3 * I[R_SITE1] + 2] - xpos[3 * fr + 2]
            ax = xmat[m9] * r0 + xmat[m9 + 3] * r1 + xmat[m9 + 6] * r2
            az = xmat[m9 + 2] * r0 + xmat[m9 + 5] * r1 + xmat[m9 + 8] * r2
            cx, cz, px, pz = _chain_pull(tr, ax, az, F[F_CHAIN_RING], F[F_CHAIN_COG])
            pull_x = 0.0
            pull_z = 0.0
            if cx != 0.0 or cz != 0.0:
                pull_x = xmat[m9] * cx + xmat[m9 + 2] * cz
                pull_z = xmat[m9 + 6] * cx + xmat[m9 + 8] * cz
                tr = 0.0
                ctrl[I[R_A_CR]] = 0.0
                o = 6 * I[R_WHEEL1]
                xfrc[o] += pull_x
                xfrc[o + 2] += pull_z
            # on the frame at the chainring's tangent point: -pull and its moment about the frame's centre of mass
            at_x = xpos[3 * fr] + xmat[m9] * px + xmat[m9 + 2] * pz - xipos[3 * fr]
            at_z = xpos[3 * fr + 2] + xmat[m9 + 6] * px + xmat[m9 + 8] * pz - xipos[3 * fr + 2]
            o = 6 * fr
            xfrc[o] = -pull_x
            xfrc[o + 1] = 0.0
            xfrc[o + 2] = -pull_z
            xfrc[o + 3] = 0.0
            xfrc[o + 4] = at_z * -pull_x - at_x * -pull_z
            xfrc[o + 5] = 0.0
            if I[R_DRIVE] == DRIVE_PEDAL:  # the foot on its pedal (the frame's), its reaction on the rider there
                wfx = xmat[m9] * foot_x + xmat[m9 + 2] * foot_z
                wfz = xmat[m9 + 6] * foot_x + xmat[m9 + 8] * foot_z
                px_w = xpos[3 * fr] + xmat[m9] * foot_px + xmat[m9 + 2] * foot_pz
                pz_w = xpos[3 * fr + 2] + xmat[m9 + 6] * foot_px + xmat[m9 + 8] * foot_pz
                arm_x = px_w - xipos[3 * fr]
                arm_z = pz_w - xipos[3 * fr + 2]
                xfrc[o] += wfx
                xfrc[o + 2] += wfz
                xfrc[o + 4] += arm_z * wfx - arm_x * wfz
                rb = I[R_RIDER]
                arm_x = px_w - xipos[3 * rb]
                arm_z = pz_w - xipos[3 * rb + 2]
                o = 6 * rb
                xfrc[o] = -wfx
                xfrc[o + 1] = 0.0
                xfrc[o + 2] = -wfz
                xfrc[o + 3] = 0.0
                xfrc[o + 4] = -(arm_z * wfx - arm_x * wfz)
                xfrc[o + 5] = 0.0
        o = 6 * I[R_REACT1]
        xfrc[o + 3] = 0.0
        xfrc[o + 4] = tr
        xfrc[o + 5] = 0.0
        if I[R_CALIPER] != 0:  # a four-bar's caliper link turns otherwise than the arm (BikeCallback)
            CAL = _numba.carray(_f64_pointer(I[R_CALIPER]), (nl,))
            tau = tr if tr > 0.0 else 0.0
            qfrc[I[R_SV]] = (_leverage_ratio(LW, CAL, i, w) - 1.0) * tau * xaxis[3 * I[R_ARM_JOINT] + 1]

    COMPILE_SECONDS = time.perf_counter() - _compile_start

_DISPATCHER = None
_DISPATCHER_LOCK = threading.Lock()


def _dispatcher(model):
    """The compiled bike dispatcher, its registry header filled with the mjData offsets (checked
    against live arrays of ``model``)."""
    global _DISPATCHER
    with _DISPATCHER_LOCK:
        if _DISPATCHER is None:
            if _numba is None:
                raise RuntimeError(FALLBACK_MESSAGE)
            reason = verify(model)
            if reason is not None:
                raise RuntimeError(reason)
            try:
                kinematics = kinematics_layout(model)
            except RuntimeError as error:
                raise RuntimeError(f"compiled bike callback unavailable ({error}): using the Python bike callback") \
                    from error
            REGISTRY.bind_layout({**mjdata_layout(), **kinematics})
            _DISPATCHER = _dispatch
        return _DISPATCHER


def available() -> bool:
    """True when the compiled bike path can run here."""
    return unavailable_reason() is None


def _int_field(index: int, doc: str):
    def get(self):
        return int(_INTS[self.slot, index]) if self._finalizer.alive else self._closed.get(index, 0)

    return property(get, doc=doc)


class CompiledBikeCallback(CompiledShell, ctypes._CFuncPtr):
    """Compiled counterpart of ``mtbmj.bike.callback.BikeCallback`` (same constructor): a C function
    pointer for ``mujoco.set_mjcb_control`` / ``controllers.installed``. It acts only on
    ``bike.model`` (a newer callback for the same model retires it). ``reset()`` forgets the contact
    patches; ``calls``, ``refreshes`` and ``overflowed`` are read back from the compiled slot."""

    _flags_ = ctypes._FUNCFLAG_CDECL
    _argtypes_ = (ctypes.c_void_p, ctypes.c_void_p)
    _restype_ = None
    registry = REGISTRY

    def __new__(cls, bike, fork_law, shock_law, front, rear, drive, speed, traction, refresh):
        reason = unavailable_reason()
        if reason is not None:
            raise RuntimeError(reason)
        return super().__new__(cls, _dispatcher(bike.model).address)

    def __init__(self, bike, fork_law, shock_law, front, rear, drive, speed, traction, refresh):
        from mtbmj.rolling import terrain as terrain_mod
        from mtbmj.rolling import tire as tire_model

        fork_ints, fork_floats = flatten(fork_law)  # UnsupportedLaw for a law with no compiled form
        shock_ints, shock_floats = flatten(shock_law)
        for tire in (front, rear):
            if type(tire) is not tire_model.RadialTire:
                raise UnsupportedRolling(f"tire {type(tire).__name__} has no compiled form")
        ter = front.terrain
        if type(ter) is not terrain_mod.Terrain or rear.terrain is not ter:
            raise UnsupportedRolling(f"terrain {type(ter).__name__} has no compiled form")
        if drive.mode not in ("rider", "coast", "pedal"):
            raise UnsupportedRolling(f"drive {drive.mode!r} has no compiled form on the bike")
        m = bike.model
        self._model = m  # keeps the mjModel (and so its address) alive while the slot is used
        self._address = m._address
        self.bike, self.fork, self.shock = bike, fork_law, shock_law
        self.tires = (front, rear)
        self.drive, self.speed, self.traction, self.refresh = drive, float(speed), float(traction), float(refresh)
        self._closed: dict = {}
        # arrays the slot points into (owned here, never reallocated)
        self._tx = np.ascontiguousarray(ter.x, dtype=np.float64)
        self._tz = np.ascontiguousarray(ter.z, dtype=np.float64)
        n = int(self._tx.size)
        if n < 1 or self._tz.size != n or not np.all(np.diff(self._tx) >= 0.0):
            raise UnsupportedRolling("terrain profile is empty, ragged or not sorted")
        cap = n + 2
        self._scratch = np.zeros(2 * cap, dtype=np.float64)  # the search's, one wheel after the other
        self._run = rolling.run_scratch(n, front, rear)  # a run's pieces (run_minima), one wheel after the other
        self._sx, self._sz = rolling.stretch_arrays(front)  # the corners of the terrain's straight stretches
        self._pfirst, self._pieces = rolling.piece_table(self._tx, self._tz, tire_model.PIECE_M)  # cut once, read by both
        lev = bike.spec.leverage
        self._lw, self._lr, self._ls = (np.array(v, dtype=np.float64) for v in lev.table)
        caliper = bike.spec.caliper_ratio  # a four-bar's rear caliper's turn per the arm's, on the same table
        self._cal = None if caliper is None else np.ascontiguousarray(caliper, dtype=np.float64)
        self._mass = np.ascontiguousarray(m.body_mass, dtype=np.float64)
        self._roots = np.ascontiguousarray(m.body_rootid, dtype=np.int64)

        a = lambda name: int(m.actuator(name).id)  # noqa: E731
        sites = (int(m.site("front_axle").id), int(m.site("rear_axle").id))
        ints = np.zeros(INT_WIDTH, dtype=np.int64)
        values = {
            R_FQ: bike.qpos_index("fork"), R_FV: bike.dof_index("fork"), R_SV: bike.dof_index("swingarm"),
            R_A_FORK: a("fork_force"), R_A_SHOCK: a("shock_torque"), R_A_FS: a("fork_friction_state"),
            R_A_SS: a("shock_friction_state"), R_A_TX0: a("front_tire_x"), R_A_TZ0: a("front_tire_z"),
            R_A_TX1: a("rear_tire_x"), R_A_TZ1: a("rear_tire_z"), R_A_DX: a("drive_x"), R_A_DZ: a("drive_z"),
            R_A_PROBE0: a("front_deflection_probe"), R_A_PROBE1: a("rear_deflection_probe"),
            R_A_SHOCK_PROBE: a("shock_force_probe"), R_SITE0: sites[0], R_SITE1: sites[1],
            R_SBODY0: int(m.site_bodyid[sites[0]]), R_SBODY1: int(m.site_bodyid[sites[1]]),
            R_FRAME: int(m.body("frame").id), R_NBODY: int(m.nbody), R_MASS: self._mass.ctypes.data,
            R_BODYROOT: self._roots.ctypes.data, R_WHEEL0: int(m.body("front_wheel").id),
            R_WHEEL1: int(m.body("rear_wheel").id), R_REACT0: int(m.body("fork_lower").id),
            R_REACT1: int(m.body("swingarm").id),
            R_A_GFX: a("front_ground_x"), R_A_GFZ: a("front_ground_z"), R_A_CF: a("front_couple"),
            R_A_CR: a("rear_couple"),
            R_FORK_STATE: int(bool(fork_law.has_state)), R_SHOCK_STATE: int(bool(shock_law.has_state)),
            R_DRIVE: {"coast": 0, "rider": 1, "pedal": DRIVE_PEDAL}[drive.mode], R_NL: self._lw.size, R_LW: self._lw.ctypes.data,
            R_LR: self._lr.ctypes.data, R_LS: self._ls.ctypes.data,
            R_CALIPER: 0 if self._cal is None else self._cal.ctypes.data}
        legs, arms = bike.limbs
        values.update({R_LIMB_F0: int(m.site(legs.frame_site).id), R_LIMB_R0: int(m.site(legs.rider_site).id),
                       R_LIMB_F1: int(m.site(arms.frame_site).id), R_LIMB_R1: int(m.site(arms.rider_site).id),
                       R_JZ: int(m.joint("rider_z").id), R_JP: int(m.joint("rider_pitch").id),
                       R_VZ: bike.dof_index("rider_z"), R_VP: bike.dof_index("rider_pitch"),
                       R_XQ: bike.qpos_index("bike_x"), R_PITCHQ: bike.qpos_index("pitch"), R_ARM_JOINT: int(m.joint("swingarm").id),
                       R_RIDER: int(m.body("rider").id)})
        values[R_ACT_F] = int(m.actuator_actadr[values[R_A_FS]])
        values[R_ACT_S] = int(m.actuator_actadr[values[R_A_SS]])
        values[R_ROOT0] = int(m.body_rootid[values[R_SBODY0]])
        values[R_ROOT1] = int(m.body_rootid[values[R_SBODY1]])
        for index, value in values.items():
            ints[index] = value
        floats = np.zeros(FLOAT_WIDTH, dtype=np.float64)
        floats[[F_SPEED, F_TRACTION, F_REFRESH]] = [self.speed, self.traction, self.refresh]
        floats[F_TOTAL_MASS] = float(m.body_subtreemass[values[R_FRAME]])
        floats[F_PIVOT_X], floats[F_REAR_Z0] = bike.spec.pivot[0], bike.spec.rear_axle[1]
        floats[[F_NEXT0, F_NEXT1]] = -math.inf
        floats[[F_LAST0, F_LAST1]] = math.inf
        floats[F_REFRESH_DISTANCE] = tire_model.REFRESH_DISTANCE_M
        floats[[F_LIMB_K0, F_LIMB_C0, F_LIMB_REST0]] = [legs.stiffness, legs.damping, legs.rest]
        floats[[F_LIMB_K1, F_LIMB_C1, F_LIMB_REST1]] = [arms.stiffness, arms.damping, arms.rest]
        floats[[F_DRIVE_KV, F_DRIVE_PUSH, F_DRIVE_POWER, F_DRIVE_BRAKE]] = [drive.kv, drive.push, drive.power,
                                                                          drive.brake]
        floats[F_RADIUS] = rear.radius
        floats[[F_LIFT_LO, F_LIFT_HI]] = LIFT_EASE_DEG  # the rider eases off as the front lifts
        chain = bike.spec.drive.get("chain_m")  # (chainring, cog) pitch radii, m; 0: a hub drive
        if chain is not None:
            floats[[F_CHAIN_RING, F_CHAIN_COG]] = chain
        wheel_ints = np.zeros(2 * WI, dtype=np.int64)
        wheel_floats = np.zeros(2 * WF, dtype=np.float64)
        for k, tire in enumerate((front, rear)):
            # the front end's slot layout: the terrain, the straight stretches and the scratch of the search
            wheel = wheel_ints[k * WI:(k + 1) * WI]
            wheel[[rolling.R_NPTS, rolling.R_CAP, rolling.R_TX, rolling.R_TZ, rolling.R_SCRATCH]] = [
                n, cap, self._tx.ctypes.data, self._tz.ctypes.data, self._scratch.ctypes.data]
            wheel[[rolling.R_NS, rolling.R_SX, rolling.R_SZ]] = [self._sx.size, self._sx.ctypes.data,
                                                                 self._sz.ctypes.data]
            wheel[[rolling.R_PFIRST, rolling.R_PIECES, rolling.R_NPIECES]] = [
                self._pfirst.ctypes.data, self._pieces.ctypes.data, self._pieces.size // 4]
            wheel[[rolling.R_RUN, rolling.R_RUNCAP]] = [self._run.ctypes.data,
                                                         self._run.size // (rolling.RUN_BLOCKS + tire_model.SHARE_BLOCKS)]
            row = wheel_floats[k * WF:(k + 1) * WF]
            row[[rolling.F_RADIUS, rolling.F_RATE, rolling.F_DAMPING, rolling.F_MARGIN]] = [
                tire.radius, tire.rate, tire.damping, tire.margin]
            row[rolling.F_PIECE] = tire_model.PIECE_M
            if tire.rim is not None:
                row[[rolling.F_RIM_D, rolling.F_RIM_K, rolling.F_RIM_C, rolling.F_RIM_P0]] = [
                    tire.rim.max_deflection, tire.rim.rate, tire.rim.damping, STIFFENING_M]
        slot = REGISTRY.claim(m._address, {"ints": ints, "floats": floats, "wheel_ints": wheel_ints,
                                           "wheel_floats": wheel_floats, "fork_ints": fork_ints,
                                           "fork_floats": fork_floats, "shock_ints": shock_ints,
                                           "shock_floats": shock_floats}, "compiled bike callbacks")
        self.slot = slot
        self._finalizer = weakref.finalize(self, REGISTRY.release, slot)

    calls = _int_field(R_CALLS, "calls for this callback's model")
    refreshes = _int_field(R_REFRESHES, "geometry searches (patch refreshes off a straight stretch)")

    @property
    def pedal_power(self) -> float:
        """Pedalling: the power (W) the stroke asks at the next evaluation (``BikeCallback.pedal_power``)."""
        return float(_FLOATS[self.slot, F_DRIVE_POWER])

    @pedal_power.setter
    def pedal_power(self, watts: float) -> None:
        _FLOATS[self.slot, F_DRIVE_POWER] = watts

    @property
    def overflowed(self) -> bool:
        """True if a tire met more than MAX_PATCHES patches (the run must be redone in Python)."""
        if not self._finalizer.alive:
            return bool(self._closed.get("overflow", 0))
        return bool(_WINTS[self.slot, rolling.R_OVERFLOW] or _WINTS[self.slot, WI + rolling.R_OVERFLOW])

    def patches(self, k: int) -> list[tuple[float, ...]]:
        """Wheel k's (0 front, 1 rear) contact patches: (qx, qz, nx, nz, surface vx, surface vz, share,
        prominence): ``RadialTire.patches``."""
        n = int(_WINTS[self.slot, k * WI + rolling.R_NPATCH])
        o = k * WF + rolling.F_PATCHES
        w = rolling.PATCH_WIDTH
        return [tuple(float(v) for v in row) for row in _WFLOATS[self.slot, o:o + w * n].reshape(n, w)]

    def set_speed(self, v: float) -> None:
        """The drive's set speed (m/s) from the next evaluation on (``BikeCallback.set_speed``)."""
        self.speed = float(v)
        _FLOATS[self.slot, F_SPEED] = self.speed

    @property
    def plain_search(self) -> bool:
        """True: both wheels' patch search as it was before its shortcuts (``R_PLAIN``: each segment
        cut at each search, every run through ``share_depths``): the same patches to the bit, slower;
        the baseline of ``tests/test_patch_search.py`` and ``benchmarks/patch_search.py``."""
        return bool(_WINTS[self.slot, rolling.R_PLAIN])

    @plain_search.setter
    def plain_search(self, value: bool) -> None:
        for k in (0, 1):
            _WINTS[self.slot, k * WI + rolling.R_PLAIN] = int(bool(value))

    def reset(self) -> None:
        """Forget the patches: the next evaluation searches afresh (BikeCallback.reset)."""
        for k in (0, 1):
            _WINTS[self.slot, k * WI + rolling.R_NPATCH] = 0
            _WINTS[self.slot, k * WI + rolling.R_VALID] = 0
        _FLOATS[self.slot, [F_NEXT0, F_NEXT1]] = -math.inf
        _FLOATS[self.slot, [F_LAST0, F_LAST1]] = math.inf

    def counters(self) -> dict:
        """The slot's counters (kept by ``close``)."""
        return {R_CALLS: int(_INTS[self.slot, R_CALLS]), R_REFRESHES: int(_INTS[self.slot, R_REFRESHES]),
                "overflow": int(self.overflowed)}

    def __repr__(self):
        return f"<CompiledBikeCallback slot={getattr(self, 'slot', None)}>"


__all__ = ["CompiledBikeCallback", "UnsupportedLaw", "UnsupportedRolling", "available", "warn_once", "MAX_PATCHES",
           "kinematics_layout", "REGISTRY"]
