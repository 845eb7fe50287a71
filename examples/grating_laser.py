"""A sinusoidal diffraction grating under three laser lines: orders at sin θm = sin θi + m λ/Λ.

The nano surface is a height field, so the Kirchhoff fft solver computes the lobe; only the three laser lines are
simulated (the spectral pipeline knows a line SPD carries light nowhere else).

Run:  python examples/grating_laser.py [OUTDIR] [--fast]
"""
import sys
from pathlib import Path

import numpy as np
from scipy.signal import find_peaks

from waveoptics import simulate, surfaces

fast = "--fast" in sys.argv
out = Path(next((a for a in sys.argv[1:] if not a.startswith("--")), "out/grating_laser"))
period, amplitude, theta_i = 3e-6, 60e-9, 20.0

grating = surfaces.sinusoid(amplitude=amplitude, period=period, size=48e-6 if fast else 96e-6,
                            samples=384 if fast else 1024)
sim = simulate.simulate("Al", surface=grating, micro_alpha=0.005, ndf="ggx", incident=(theta_i, 0.0),
                        illuminant="laser:450,532,635", resolution=64 if fast else 256, solver="fft",
                        sphere=not fast)
print("simulated wavelengths:", sim.wavelengths_nm)
theta, f = simulate.plane_of_incidence(sim, "total", n=4001)
for i, lam in enumerate(sim.wavelengths_nm):
    predicted = [np.degrees(np.arcsin(np.sin(np.radians(theta_i)) + m * lam * 1e-9 / period))
                 for m in range(-3, 4) if abs(np.sin(np.radians(theta_i)) + m * lam * 1e-9 / period) < 1]
    peaks, _ = find_peaks(f[i], height=1e-3 * f[i].max())
    found = [round(float(theta[p]), 1) for p in peaks]
    print(f"{lam:.0f} nm: predicted orders at θo = {np.round(predicted, 1)} deg; lobe peaks at {found}")
if not fast:
    simulate.write_outputs(sim, out, overwrite=True)
    print(f"pictures in {out}/")
