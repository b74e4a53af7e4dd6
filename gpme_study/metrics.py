"""Metrics of one sweep point computed from run histories (DataFrames of
gpme_core.integrate.simulate).  Pure functions: no runs here (those are in point.py).

Signals, all sampled at the recorded rows t_k (s):
  q_f(t)   (n_f,) rad   the RFEM coordinates psi/theta/phi_arm_r of the flexible run
  dr(t)    (3,)   m     end-effector deviation caused by flexibility: r_E of the flexible
                        run minus r_E of the rigid run at the same parameters and times, both
                        started on the constraint manifold (world frame)
  F_r(t)   (n,)         constraint reaction generalized forces A^T lambda
                        (M q_ddot = h + Q + A^T lambda); the psi3 entry (N m) and z4 entry
                        (N) are what ideal drives on psi3 and z4 would have to deliver
"""
import numpy as np
from scipy import signal

# name -> (unit, definition, can be bounded in a safe region)
METRICS = {
    "flex_peak_rad": ("rad", "max over t and over the RFEM coordinates of |q_f|", True),
    "flex_rms_rad": ("rad", "RMS over t of the Euclidean norm of q_f", True),
    "dev_peak_m": ("m", "max over t of |dr|: flexible minus rigid end-effector position", True),
    "dev_rms_m": ("m", "RMS over t of |dr|", True),
    "vib_peak_m": ("m", "max of |dr_hp| over transient <= t <= t_end - 2/min_frequency_hz, "
                   "dr high-passed at min_frequency_hz (the vibration without the "
                   "quasi-static sag; the window leaves out the filter's end effects)", True),
    "psi3_dev_peak_rad": ("rad", "max over t of |psi3 flexible - psi3 rigid|: how differently "
                          "the psi3 drive must move to make the flexible arm follow", True),
    "z4_dev_peak_m": ("m", "max over t of |z4 flexible - z4 rigid|, the same for z4", True),
    "stress_peak_Pa": ("Pa", "max over t and over the arm's sdes of the bending stress from "
                       "the sde moments (gpme_core.elastic_loads); elastic below yield / 1.5",
                       True),
    "vib_freq_hz": ("Hz", "frequency of the largest peak above min_frequency_hz of the summed "
                    "power spectra of q_f after the transient", False),
    "drive_psi3_peak_Nm": ("N m", "max over t of |F_r[psi3]| in the flexible run: peak torque "
                           "of an ideal drive on psi3", True),
    "drive_z4_peak_N": ("N", "max over t of |F_r[z4]| in the flexible run: peak force of an "
                        "ideal drive on z4", True),
    "rigid_drive_psi3_peak_Nm": ("N m", "the same for the rigid run", True),
    "rigid_drive_z4_peak_N": ("N", "the same for the rigid run", True),
    "phi1_max_abs": ("1", "max |Phi_1| (ellipse, dimensionless) after the transient", True),
    "phi2_max_abs_m": ("m", "max |Phi_2| (height programme) after the transient", True),
    "constraints_met": ("bool", "the runs finished and max |Phi| after the transient <= "
                        "phi_tolerance", False),
    "wall_time_s": ("s", "wall time of the point: both runs and the metrics", True),
}
# Butterworth order of the high-pass that separates vibration from quasi-static deviation:
# 4 gives -48 dB/octave, enough to remove the 1/T-harmonics of the programmed motion when
# min_frequency_hz sits a few octaves above 1/T, while ringing stays small.
HIGHPASS_ORDER = 4
# The zero-phase filter's padding (odd extension) turns the curvature of the slow part at
# the record's ends into a spurious transient decaying over a few corner periods; for a
# 0.4 Hz part against a 2 Hz corner it was measured at 56 % of the slow part's curvature
# term at the end, 1 % of it 2 corner periods inside.  vib_peak_m leaves these out.
EDGE_PERIODS = 2.0


def flexible_columns(model):
    """Names of the RFEM coordinates of ``model`` (empty for a rigid model)."""
    return [model.coordinate_names[k] for info in model.flexible_links
            for k in info.joint_indices]


def flexible_coordinate_metrics(df, columns):
    """{flex_peak_rad, flex_rms_rad} of the columns ``columns`` of ``df`` (rad)."""
    if not columns:
        return {"flex_peak_rad": np.nan, "flex_rms_rad": np.nan}
    q_f = df[columns].to_numpy()
    return {"flex_peak_rad": float(np.abs(q_f).max()),
            "flex_rms_rad": float(np.sqrt(np.mean(np.sum(q_f ** 2, axis=1))))}


def end_effector_deviation(flexible, rigid):
    """dr (n_rows, 3) m: (x_E, y_E, z_E) of ``flexible`` minus those of ``rigid``, the rigid
    history linearly interpolated to the flexible run's times if the grids differ."""
    t = flexible.t.to_numpy()
    r_f = flexible[["x_E", "y_E", "z_E"]].to_numpy()
    if len(rigid) == len(flexible) and np.allclose(rigid.t.to_numpy(), t, rtol=0, atol=1e-12):
        r_r = rigid[["x_E", "y_E", "z_E"]].to_numpy()
    else:
        r_r = np.column_stack([np.interp(t, rigid.t.to_numpy(), rigid[c].to_numpy())
                               for c in ("x_E", "y_E", "z_E")])
    return r_f - r_r


def dependent_deviation(flexible, rigid):
    """{psi3_dev_peak_rad, z4_dev_peak_m}: peak difference of the dependent coordinates of
    two runs recorded at the same times."""
    return {"psi3_dev_peak_rad": float(np.abs(flexible.psi3 - rigid.psi3).max()),
            "z4_dev_peak_m": float(np.abs(flexible.z4 - rigid.z4).max())}


def highpass(x, fs, cutoff):
    """x (n, k) high-passed at ``cutoff`` Hz (zero-phase Butterworth, sampling rate fs Hz)."""
    if not 0 < cutoff < 0.5 * fs:
        return x - x.mean(axis=0)
    sos = signal.butter(HIGHPASS_ORDER, cutoff, btype="highpass", fs=fs, output="sos")
    return signal.sosfiltfilt(sos, x, axis=0)


def deviation_metrics(dr, fs, min_frequency_hz, transient=0.0):
    """{dev_peak_m, dev_rms_m, vib_peak_m} of dr (n_rows, 3) m sampled at fs Hz from t = 0.

    vib_peak_m looks at t >= transient (s) and leaves out the last EDGE_PERIODS corner
    periods (EDGE_PERIODS / min_frequency_hz s), where the filter's end effect sits; if
    that leaves no samples the whole record is used."""
    norm = np.linalg.norm(dr, axis=1)
    vib = np.linalg.norm(highpass(dr, fs, min_frequency_hz), axis=1)
    t = np.arange(len(dr)) / fs
    edge = EDGE_PERIODS / min_frequency_hz if min_frequency_hz > 0 else 0.0
    window = (t >= transient) & (t <= t[-1] - edge)
    return {"dev_peak_m": float(norm.max()), "dev_rms_m": float(np.sqrt(np.mean(norm ** 2))),
            "vib_peak_m": float(vib[window].max() if window.any() else vib.max())}


def dominant_frequency(x, fs, min_frequency_hz):
    """Hz: frequency of the largest peak above ``min_frequency_hz`` of the summed power
    spectra of the columns of x (n, k), each detrended and Hann-windowed; the peak is refined
    by a parabola through the log power of the three bins around it.  NaN if x has no
    variation or fewer than 8 rows."""
    x = np.asarray(x, dtype=float)
    if x.ndim == 1:
        x = x[:, None]
    if len(x) < 8:
        return np.nan
    x = signal.detrend(x, axis=0, type="linear")
    win = np.hanning(len(x))[:, None]
    power = (np.abs(np.fft.rfft(x * win, axis=0)) ** 2).sum(axis=1)
    freqs = np.fft.rfftfreq(len(x), 1.0 / fs)
    band = np.flatnonzero(freqs >= max(min_frequency_hz, freqs[1]))
    if len(band) == 0 or not np.any(power[band] > 0):
        return np.nan
    k = band[np.argmax(power[band])]
    if 0 < k < len(power) - 1 and np.all(power[k - 1:k + 2] > 0):
        lp = np.log(power[k - 1:k + 2])
        denom = lp[0] - 2 * lp[1] + lp[2]
        shift = 0.5 * (lp[0] - lp[2]) / denom if denom < 0 else 0.0
        return float(freqs[k] + np.clip(shift, -0.5, 0.5) * (freqs[1] - freqs[0]))
    return float(freqs[k])


def reaction_history(system, df):
    """F_r (n_rows, n): the constraint reaction generalized forces A^T lambda at each row
    of the run ``df`` of ``system`` (units of each coordinate's generalized force)."""
    names = list(system.model.coordinate_names)
    q = df[names].to_numpy()
    q_dot = df[[f"{nm}_dot" for nm in names]].to_numpy()
    return np.array([system.solve(t, qk, qdk).reaction_forces
                     for t, qk, qdk in zip(df.t.to_numpy(), q, q_dot)])


def drive_peaks(system, df, prefix=""):
    """{<prefix>drive_psi3_peak_Nm, <prefix>drive_z4_peak_N}: peak |A^T lambda| at psi3, z4."""
    f_r = reaction_history(system, df)
    model = system.model
    return {f"{prefix}drive_psi3_peak_Nm": float(np.abs(f_r[:, model.index("psi3")]).max()),
            f"{prefix}drive_z4_peak_N": float(np.abs(f_r[:, model.index("z4")]).max())}


def constraint_metrics(df, transient):
    """{phi1_max_abs, phi2_max_abs_m}: largest |Phi_1|, |Phi_2| at t >= transient (s)."""
    late = df[df.t >= transient]
    return {"phi1_max_abs": float(late.Phi_1.abs().max()),
            "phi2_max_abs_m": float(late.Phi_2.abs().max())}
