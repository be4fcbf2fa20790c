"""Write sway.txt, the tank's sway for case.toml: a sine at the first mode's linear
frequency under a Hann window of three periods (displacement and velocity zero at both
ends), then the tank held still until T_END. Columns: time (s), displacement along x (m).

    python cases/sloshing_free/make_sway.py
"""

import math
from pathlib import Path

L, H, G = 1.0, 0.3, 9.81          # tank length, water depth (m), gravity (m/s^2)
AMPLITUDE = 1.0e-3                # m, peak sway of the sine before the window
CYCLES = 3                        # periods of forcing
T_END = 14.0                      # s: the file covers the whole run
DT = 1.0e-3                       # s between samples

k = math.pi / L
omega = math.sqrt(G * k * math.tanh(k * H))
period = 2.0 * math.pi / omega
t_stop = CYCLES * period

lines = [f"# sway of the sloshing_free tank: {AMPLITUDE * 1e3:g} mm sine at T1 = {period:.6f} s "
         f"under a Hann window of {CYCLES} periods (stops at t = {t_stop:.6f} s), then still",
         "time_s x_m"]
n = int(round(T_END / DT))
for i in range(n + 1):
    t = i * DT
    x = 0.0
    if t < t_stop:
        x = AMPLITUDE * 0.5 * (1.0 - math.cos(2.0 * math.pi * t / t_stop)) * math.sin(omega * t)
    lines.append(f"{t:.4f} {x:.9e}")
Path(__file__).with_name("sway.txt").write_text("\n".join(lines) + "\n")
print(f"T1 = {period:.6f} s, forcing stops at t = {t_stop:.6f} s")
