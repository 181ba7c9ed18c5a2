"""What the wrench path's fit found besides the payload, and its own verdict rules.

The sensor's bias (its mean over the motion, std, drift) and the wrench's delay; the joint
torques' own unknowns where they were fitted alongside; the mass's std by error source; the
rules ``trust`` does not have (the URDF's tool, the two sources' agreement). Used by
``wrench_dynamic``.
"""

from __future__ import annotations

import numpy as np

from comgrasp_pin.estimation import block_sandwich as bs
from comgrasp_pin.estimation import dynamic_uncertainty as du
from comgrasp_pin.robot_io.from_motion import wrench_combined as wc
from comgrasp_pin.robot_io.from_motion.dynamic_fit import DATA_PART
from comgrasp_pin.robot_io.from_motion.motion_system import DRIFT_DEGREE
from comgrasp_pin.robot_io.from_motion.payload_system import NOMINAL
from comgrasp_pin.robot_io.results.estimate_result import TOOL_NOMINAL, JointTorques
from comgrasp_pin.robot_io.results.trust import nominal_tool_reasons


def tool_cov(P: np.ndarray, st: wc.Stacked, cov: np.ndarray) -> np.ndarray:
    """The tool's (10, 10) covariance ``cov`` carried to the unknowns of ``P`` (d them / d b).

    The tool's parameters enter the wrench's rows of ``st`` as A_pi (subtracted), so
    d unknowns / d tool = -P A_pi over those rows.
    """
    rows = st.rows(wc.WRENCH)
    D = -P[:, rows] @ st.A_pi.reshape(-1, 10)[rows]
    return D @ cov @ D.T


def std_parts(data_cov, cov_tool, tool, cov_arm) -> dict:
    """The mass's std (kg) by source: the data and the model, the tool, the arm model."""
    parts = {DATA_PART: float(np.sqrt(data_cov[0, 0]))}
    if tool.cov.any():
        parts[f"tool ({tool.source})"] = float(np.sqrt(cov_tool[0, 0]))
    if cov_arm is not None:
        parts["arm model"] = float(np.sqrt(cov_arm[0, 0]))
    return parts


def sensor_bias(A, b, w, st, duration, x, tool_params_cov):
    """The sensor's bias (mean over the motion), its std, its drift and the wrench's delay.

    ``x``: the fit's extra unknowns, the wrench's first (bias, drift, delay); the bias's std
    from white noise widened by the block sandwich, plus the tool's (``tool_params_cov``).
    """
    k, r = st.b.shape
    p = 16  # pi and the six biases
    blocks = du.contiguous_blocks(k, du.block_count(duration))
    white = du.white_cov(A, b, w, p)[10:, 10:]
    block = bs.block_cov(A, b, w, k, r, blocks, p)[10:, 10:]
    var = np.maximum(np.diag(white), np.diag(block))
    var += np.diag(tool_cov(du.sensitivity(A, w, p)[10:], st, tool_params_cov))
    extras = x[: 6 * (1 + DRIFT_DEGREE)].reshape(1 + DRIFT_DEGREE, 6)
    drift = 2 * extras[1 : 1 + DRIFT_DEGREE : 2].sum(axis=0)
    return extras[0], np.sqrt(var), drift, float(x[6 * (1 + DRIFT_DEGREE)])


def wrench_reasons(tool, agree, joint_source) -> list[str]:
    """The wrench path's own objections: the URDF's tool, the two sources' agreement.

    ``trust.motion_reasons`` has the ones every motion shares.
    """
    reasons = nominal_tool_reasons(tool.source == TOOL_NOMINAL, float(tool.params[0]))
    if agree is not None and agree["disagree"]:
        m = agree["mass_kg"]
        ratio = np.abs(agree["z"]) / np.array(agree["max_z"])
        i = int(np.argmax(ratio))
        reasons.append(
            f"the wrench and the joint torques disagree ({['mass', 'm c_x', 'm c_y', 'm c_z'][i]}"
            f" {abs(agree['z'][i]):.1f} std apart, at most {agree['max_z'][i]:.1f} for its "
            f"{agree['cov_dof'][i]:.0f} degrees of freedom; masses {m['wrench']:.3f} "
            f"and {m['joint_torques']:.3f} kg): "
            + ("the URDF's model of the arm is the likely cause; give an empty run of the same "
               "motion or an identified arm model, or leave the joint torques out"
               if joint_source == NOMINAL else
               "a sensor's scale, the tool, or the arm model is wrong")
        )  # fmt: skip
    return reasons


def joint_part(J, x, e_w, st, predicted, payload, note) -> JointTorques | None:
    """The joint torques' own findings in the combined fit, or None without them."""
    if J is None:
        return None
    cols = st.groups[wc.JOINT_TORQUES][0]
    n = len(cols)
    extras = x[e_w : e_w + J.per_joint * n].reshape(J.per_joint, n)
    res = predicted[:, cols] - payload[:, cols]
    return JointTorques(
        st.noise[6:], "residuals", J.source, offsets=extras[0],
        offset_drift=2 * extras[1 : 1 + DRIFT_DEGREE : 2].sum(axis=0),
        friction=extras[1 + DRIFT_DEGREE :].T if J.source == NOMINAL else None,
        residual_rms=np.sqrt(np.mean(res**2, axis=0)),
        delay_s=None if J.alignment is not None else float(x[-1]), alignment=J.alignment,
        tau_payload=payload[:, cols], tau_payload_fit=predicted[:, cols], note=note,
    )  # fmt: skip
