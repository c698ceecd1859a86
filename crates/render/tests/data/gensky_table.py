"""Radiance gensky's own numbers for a set of skies: the table `luxest_render::sky`'s test
`agrees_with_gensky` reads (crates/render/tests/data/gensky.csv).

    .venv-peers/bin/python crates/render/tests/data/gensky_table.py

Each row: gensky's arguments, then what it prints — the solar direction (x east, y north, z up;
from the sun source, or the sky function's last three arguments), the sky function's zenith
brightness, ground brightness and normalisation F2 (0 for overcast skies), and the solar
radiance (0 without a sun), in Radiance's units (W/sr/m²).
"""

import subprocess
from pathlib import Path

import pyradiance  # noqa: F401  (puts the bundled Radiance binaries on PATH)

CASES = [
    "3 21 12 -c -a 52.5 -o -13.4 -m -15",
    "6 21 10 +s -a 52.5 -o -13.4 -m -15",
    "6 21 10 +i -a 52.5 -o -13.4 -m -15",
    "12 21 9.5 +s -a 40.7 -o 74 -m 75",
    "9 2 16.25 -s -a -33.9 -o -151.2 -m -150",
    "1 15 13 +i -a 10 -o 5 -m 0 -t 4",
    "2 29 8 +s -a 60 -o -25 -m -30 -g 0.35",
    "7 4 18 +s -a 35 -o 120 -m 120",
    "11 30 +11 +s -a 45 -o 0 -m 0",
    "4 10 12 -u -a 48 -o -2 -m -15",
    "3 21 12 -c -B 55.8659 -a 52 -o 0 -m 0",
    "6 21 12 +s -b 10 -a 52 -o 0 -m 0",
    "6 21 12 +s -a 20 -o 0 -m 0",
    "12 21 12 +s -a 80 -o 0 -m 0",
    "8 15 6 -i -a 65 -o -20 -m -15",
]
ANGLES = ["-ang 35 -20 +s", "-ang 60 45 +i", "-ang 10 170 -s", "-ang 89 0 +s"]


def run(args):
    out = subprocess.run(["gensky", *args.split()], capture_output=True, text=True, check=True).stdout
    lines = [line.split() for line in out.splitlines() if line and not line.startswith("#")]
    solar, sky = 0.0, None
    for k, f in enumerate(lines):
        if f[:3] == ["void", "light", "solar"]:
            solar = float(lines[k + 3][1])
        if f[:3] == ["void", "brightfunc", "skyfunc"]:
            sky = [float(x) for x in lines[k + 3][1:]]
    zen, gnd = sky[1], sky[2]
    f2, sun = (sky[3], sky[4:7]) if len(sky) == 7 else (0.0, [0.0, 0.0, 0.0])
    return [zen, gnd, f2, *sun, solar]


def main():
    rows = ["# gensky (Radiance 6.0a from PyPI pyradiance): args; zenith, ground, F2, sun x y z, solar"]
    rows.append("args,zenith,ground,f2,sun_x,sun_y,sun_z,solar")
    for args in CASES + ANGLES:
        rows.append(",".join([args, *(repr(v) for v in run(args))]))
    out = Path(__file__).with_name("gensky.csv")
    out.write_text("\n".join(rows) + "\n")
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
