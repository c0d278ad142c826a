#!/usr/bin/env python3
"""A biaxial LiDAR's geometric overlap against the model's linear ramp
(NOTES.md, 2026-12-04, the LiDAR's fog echoes).

Receiver focused at infinity: aperture radius A, field-of-view half-angle
phi, axis offset d from a transmitter whose spot has radius a_t + r theta/2
(uniform). A point at lateral distance rho from the receiver axis at range r
reaches the detector from the part of the aperture within r phi of it, so
its share is |disk(A) & disk(rho, r phi)| / (pi A^2); xi(r) averages that
over the spot. phi and d are chosen so that xi starts at r_1 = 1 m and is
full at r_2 = 10 m, as the model's defaults. Prints xi(r) and the peak of
xi / r^2, which sets the visibility below which fog echoes reach P_th
(V_crit ~ pi 0.046 c tau / 2 * peak / P_th without extinction).
"""
import math


def lens_area(r1, r2, d):
    if d >= r1 + r2:
        return 0.0
    if d <= abs(r2 - r1):
        return math.pi * min(r1, r2) ** 2
    a = r1 * r1 * math.acos((d * d + r1 * r1 - r2 * r2) / (2 * d * r1))
    b = r2 * r2 * math.acos((d * d + r2 * r2 - r1 * r1) / (2 * d * r2))
    k = (-d + r1 + r2) * (d + r1 - r2) * (d - r1 + r2) * (d + r1 + r2)
    return a + b - 0.5 * math.sqrt(max(0.0, k))


A_T, A, THETA, R1, R2 = 2.5e-3, 12.5e-3, 3e-3, 1.0, 10.0


def spot_radius(r):
    return A_T + THETA * r / 2


# r_1: the spot's near edge at the edge of what the aperture sees, d - R_t = r phi + A;
# r_2: the whole spot seen by the whole aperture, r phi = A + d + R_t.
PHI = (2 * A + spot_radius(R2) + spot_radius(R1)) / (R2 - R1)
D = R1 * PHI + A + spot_radius(R1)


def overlap(r, n=60):
    rt, total, count = spot_radius(r), 0.0, 0
    for i in range(n):
        for j in range(n):
            x, y = -rt + (i + 0.5) * 2 * rt / n, -rt + (j + 0.5) * 2 * rt / n
            if x * x + y * y > rt * rt:
                continue
            total += lens_area(A, r * PHI, math.hypot(D + x, y)) / (math.pi * A * A)
            count += 1
    return total / count


def main():
    print(f"field of view {2e3 * PHI:.1f} mrad (full), axis offset {1e3 * D:.1f} mm")
    peaks = {"geometric": (0.0, 0.0), "linear": (0.0, 0.0)}
    for k in range(100, 1201, 5):
        r = k / 100
        xi = {"geometric": overlap(r), "linear": min(1.0, max(0.0, (r - R1) / (R2 - R1)))}
        for name, v in xi.items():
            if v / r**2 > peaks[name][0]:
                peaks[name] = (v / r**2, r)
        if k % 100 == 0:
            print(f"r {r:5.1f} m  geometric {xi['geometric']:.3f}  linear {xi['linear']:.3f}")
    rho_per_visibility = math.pi * 0.046 * 299792458 * 5e-9 / 2
    for name, (v, r) in peaks.items():
        print(f"{name}: peak xi/r^2 {v:.4f} m^-2 at {r:.2f} m, "
              f"V_crit ~ {rho_per_visibility * v / (0.1 / 200**2):.0f} m")


if __name__ == "__main__":
    main()
