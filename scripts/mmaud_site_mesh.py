#!/usr/bin/env python3
"""Writes scenarios/meshes/mmaud_site.obj, the static world of
scenarios/mmaud_twin.json: a flat-roofed block whose roof carries the
sensing rig, beside an open car park (parked cars, lamp posts, a tree line)
and a glazed building beyond it. ENU metres, z up, the ground plane z = 0 is
uavsim's own. Deterministic (no randomness): run it again to get the same
file. Usage: scripts/mmaud_site_mesh.py [OUT.obj]
"""
import sys

out_path = sys.argv[1] if len(sys.argv) > 1 else "scenarios/meshes/mmaud_site.obj"
vertices, objects = [], []


def box(name, material, lo, hi):
    """An axis-aligned box as 12 triangles, counter-clockwise seen from outside."""
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    base = len(vertices) + 1
    for z in (z0, z1):
        for y in (y0, y1):
            for x in (x0, x1):
                vertices.append((x, y, z))
    # corner index: 1 + x + 2 y + 4 z (0-based within the box)
    quads = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    faces = []
    for a, b, c, d in quads:
        faces.append((base + a, base + b, base + c))
        faces.append((base + a, base + c, base + d))
    objects.append((name, material, faces))


# The rig's building: 40 x 40 m, roof at 12 m, a 1 m parapet, a stair housing
# and a plant unit on the roof. The rig stands near its east edge (x = -14).
box("lab_block", "concrete", (-50, -20, 0), (-10, 20, 12))
box("parapet_e", "concrete", (-10.3, -20, 12), (-10, 20, 13))
box("parapet_w", "concrete", (-50, -20, 12), (-49.7, 20, 13))
box("parapet_n", "concrete", (-50, 19.7, 12), (-10, 20, 13))
box("parapet_s", "concrete", (-50, -20, 12), (-10, -19.7, 13))
box("stair_housing", "concrete", (-45, 10, 12), (-39, 16, 15.5))
box("plant_unit", "metal", (-30, -15, 12), (-26, -12, 13.8))

# The car park east of it: x 0 .. 100, y -45 .. 45, six rows of bays 2.6 m
# wide, cars 4.6 x 1.9 x 1.5 m nose-in; a bay is empty when a fixed pattern
# says so (about a third of them).
rows = [-37.5, -22.5, -7.5, 7.5, 22.5, 37.5]
n_cars = 0
for r, yc in enumerate(rows):
    for k in range(37):
        if (k * 7 + r * 3) % 10 in (0, 4, 7):
            continue
        x0 = 4.0 + 2.6 * k + 0.35
        box(f"car_{r}_{k}", "metal_car", (x0, yc - 2.3, 0), (x0 + 1.9, yc + 2.3, 1.5))
        n_cars += 1
for i, x in enumerate((10, 40, 70, 100)):
    for j, y in enumerate((-30, 0, 30)):
        box(f"lamp_{i}_{j}", "metal", (x - 0.1, y - 0.1, 0), (x + 0.1, y + 0.1, 9))
for i, x in enumerate(range(5, 100, 12)):
    for side, y in (("s", -52), ("n", 52)):
        box(f"tree_{side}{i}", "tree", (x - 1.5, y - 1.5, 2), (x + 1.5, y + 1.5, 7))
        box(f"trunk_{side}{i}", "tree", (x - 0.2, y - 0.2, 0), (x + 0.2, y + 0.2, 2))
# Beyond the car park: a glazed block, 20 m tall.
box("office", "glass", (115, -30, 0), (145, 30, 20))

with open(out_path, "w") as f:
    f.write("# uavsim: the MMAUD twin's site (scripts/mmaud_site_mesh.py writes it), z up, metres.\n")
    f.write(f"# {len(objects)} objects ({n_cars} cars), {sum(len(o[2]) for o in objects)} triangles.\n")
    f.write("# Material names map to uavsim's built-in materials by keyword (metal, tree, glass;\n")
    f.write("# anything else is concrete).\n")
    for v in vertices:
        f.write("v %g %g %g\n" % v)
    for name, material, faces in objects:
        f.write(f"o {name}\nusemtl {material}\n")
        for a, b, c in faces:
            f.write(f"f {a} {b} {c}\n")
print(out_path, len(objects), "objects", n_cars, "cars")
