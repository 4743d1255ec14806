"""Run the hostile cases of issue 10 ("What is wrong today") and print what each does.

    python benchmarks/hostile.py

Every case runs ``python -m rigidid`` in a fresh temporary folder (device nodes and
FIFOs are made there, never in the system's /dev). Prints, per case: the exit status,
the first stderr line (and how many lines), and what was left behind.
"""

from __future__ import annotations

import os
import stat
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
S = ROOT / "samples" / "paper-1994"
F = ROOT / "samples" / "four-mounts"


def run(args: list[str], cwd: Path, *, shell: str | None = None, timeout: float = 20.0) -> tuple[str, str]:
    cmd = shell or " ".join([sys.executable, "-m", "rigidid", *args])
    t0 = time.perf_counter()
    try:
        proc = subprocess.run(
            cmd, shell=True, executable="/bin/bash", cwd=cwd, capture_output=True, text=True, timeout=timeout
        )
    except subprocess.TimeoutExpired:
        return "HANG", f"still running after {timeout:.0f} s"
    err = [line for line in proc.stderr.splitlines() if line.strip() and "rigidid: warning:" not in line]
    first = " / ".join(err) if err and len(err) <= 3 else err[0] if err else "(no stderr but warnings)"
    if any("Traceback" in line for line in err):
        first = "TRACEBACK: " + err[-1]
    return f"{proc.returncode} ({time.perf_counter() - t0:.1f} s, {len(err)} stderr lines)", first[:160]


def case(
    title: str,
    args: list[str] | None = None,
    *,
    shell: str | None = None,
    setup=None,
    check=None,
    timeout: float = 20.0,
) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        if setup:
            setup(d)
        status, first = run(
            args or [], d, shell=shell.format(py=f"{sys.executable} -m rigidid") if shell else None, timeout=timeout
        )
        left = check(d) if check else ""
        print(f"- {title}\n    status {status}\n    stderr: {first}" + (f"\n    after: {left}" if left else ""))


def chardev(d: Path) -> None:
    st = os.stat("/dev/null")
    os.mknod(d / "null", 0o666 | stat.S_IFCHR, st.st_rdev)


def uff_test(d: Path, *, drop_sensor: bool = False, modes: int = 6) -> None:
    import json

    import numpy as np

    from rigidid.io.uff import write_uff_test

    layout = json.loads((S / "layout.json").read_text())
    ids = [s["id"] for s in layout["sensors"]]
    t = np.arange(256) / 128.0
    data = np.random.default_rng(1).standard_normal((256, len(ids)))
    records = [(t, data, ids), (t, data[:, 1:] if drop_sensor else data, ids[1:] if drop_sensor else ids)]
    rows = []
    for line in (S / "modes.csv").read_text().splitlines()[1:]:
        m, f, z, sid, re, im = line.split(",")
        if int(m) <= modes:
            rows.append((int(m), float(f), float(z), sid, float(re), float(im)))
    write_uff_test(d / "t.uff", layout, records if drop_sensor else [], mode_rows=None if drop_sensor else rows)


def kind(p: Path) -> str:
    if p.is_symlink():
        return "symlink"
    if not p.exists():
        return "absent"
    m = os.stat(p).st_mode
    return "chardev" if stat.S_ISCHR(m) else "fifo" if stat.S_ISFIFO(m) else "dir" if p.is_dir() else "regular file"


def listing(d: Path) -> str:
    return ", ".join(sorted(str(p.relative_to(d)) for p in d.rglob("*"))) or "(nothing)"


def main() -> None:
    L, M, B = str(S / "layout.json"), str(S / "modes.csv"), str(F / "body.json")
    FL = str(F / "layout.json")
    print("## Damage")
    case(
        "identify --json DEVNODE (a char device like /dev/null)",
        ["identify", L, M, "--json", "null"],
        setup=chardev,
        check=lambda d: "null is " + kind(d / "null"),
    )
    case(
        "identify --uff SYMLINK (-> real.uff)",
        ["identify", L, M, "--uff", "link.uff"],
        setup=lambda d: ((d / "real.uff").write_text("old"), os.symlink("real.uff", d / "link.uff")),
        check=lambda d: f"link.uff is {kind(d / 'link.uff')}, real.uff {(d / 'real.uff').stat().st_size} bytes",
    )
    case(
        "simulate -o FIFO (reader: cat)",
        shell=f"mkfifo p; (cat p > got &) ; {{py}} simulate {B} {FL} -o p; sleep 0.3",
        check=lambda d: (
            f"p is {kind(d / 'p')}, reader got {(d / 'got').stat().st_size if (d / 'got').exists() else 0} bytes"
        ),
    )
    print("## Partial outputs")
    case(
        "identify --json o.json --uff nodir/x.uff",
        ["identify", L, M, "--json", "o.json", "--uff", "nodir/x.uff"],
        check=listing,
    )
    case(
        "modes --json e.json -o nodir/m.csv (records from simulate)",
        shell=f"{{py}} simulate {B} {FL} --records rec -o /dev/stdout >/dev/null 2>&1; rm -f x; "
        f"{{py}} modes {FL} rec/record-1.csv rec/record-2.csv --json e.json -o nodir/m.csv; rm -r rec",
        check=listing,
        timeout=60,
    )
    case(
        "simulate --records rec -o nodir/m.csv",
        ["simulate", B, FL, "--records", "rec", "-o", "nodir/m.csv"],
        check=listing,
    )
    case(
        "report -o r.html --png afile/x",
        ["report", L, M, "-o", "r.html", "--png", "afile/x"],
        setup=lambda d: (d / "afile").write_text("x"),
        check=listing,
        timeout=60,
    )
    print("## Non-finite numbers")
    case(
        "identify --mass 1e308 --json o.json",
        ["identify", L, M, "--mass", "1e308", "--json", "o.json"],
        check=lambda d: (
            "o.json has Infinity/NaN"
            if (d / "o.json").exists() and any(w in (d / "o.json").read_text() for w in ("Infinity", "NaN"))
            else listing(d)
        ),
    )
    case(
        "simulate --shape-noise inf -o m.csv", ["simulate", B, FL, "--shape-noise", "inf", "-o", "m.csv"], check=listing
    )
    print("## Tracebacks")
    case("--json adir (a directory)", ["identify", L, M, "--json", "adir"], setup=lambda d: (d / "adir").mkdir())
    case("--json '' (empty path)", ["identify", L, M, "--json", "''"])
    case(
        "simulate --records afile (a file)",
        ["simulate", B, FL, "--records", "afile"],
        setup=lambda d: (d / "afile").write_text("x"),
    )
    case("identify --json - >&- (closed stdout)", shell=f"{{py}} identify {L} {M} --json - >&-")
    case("identify >/dev/full", shell=f"{{py}} identify {L} {M} >/dev/full")
    case(
        "layout direction [0,0,1e-200]",
        ["identify", "lay.json", M],
        setup=lambda d: (d / "lay.json").write_text(
            (S / "layout.json").read_text().replace('"direction": "+z"}', '"direction": [0, 0, 1e-200]}', 1)
        ),
    )
    case("deeply nested JSON", ["identify", "lay.json", M], setup=lambda d: (d / "lay.json").write_text("[" * 100000))
    case("identify --seed -1 --uncertainty 10", ["identify", L, M, "--seed", "-1", "--uncertainty", "10"])
    case(
        "simulate --sample-rate 1e9 --records rec",
        ["simulate", B, FL, "--sample-rate", "1e9", "--records", "rec"],
        check=listing,
    )
    print("## Hangs")
    case("modes layout.json /dev/zero", ["modes", FL, "/dev/zero"], timeout=15)
    case("identify endless layout (/dev/zero as layout)", ["identify", "/dev/zero", M], timeout=15)
    print("## Lax reading")
    case(
        'duplicate key "mass":136,"mass":1',
        ["identify", "lay.json", M],
        setup=lambda d: (d / "lay.json").write_text(
            (S / "layout.json").read_text().replace('"mass": 136.0', '"mass": 136.0, "mass": 1')
        ),
    )
    case(
        "mass: true",
        ["identify", "lay.json", M],
        setup=lambda d: (d / "lay.json").write_text(
            (S / "layout.json").read_text().replace('"mass": 136.0', '"mass": true')
        ),
    )
    case(
        "modes.csv cell 1_0",
        ["identify", L, "m.csv"],
        setup=lambda d: (d / "m.csv").write_text(Path(M).read_text().replace("1,6.10087591", "1_0,6.10087591", 1)),
    )
    case(
        "modes.csv empty imag cell",
        ["identify", L, "m.csv"],
        setup=lambda d: (d / "m.csv").write_text(Path(M).read_text().replace(",0.0414\n", ",\n", 1)),
    )
    case("--json newdir/", ["identify", L, M, "--json", "newdir/"], check=listing)
    case("report --body with other units", ["report", L, M, "--body", B, "-o", "r.html"], check=listing, timeout=60)
    print("## Status and messages")
    case(
        "identify --json - | true (broken pipe)",
        shell=f"{{py}} identify {L} {M} --json - | true; echo status of rigidid: ${{{{PIPESTATUS[0]}}}} >&2",
        timeout=30,
    )
    case(
        "simulate --records rec -o - | head -c1 (broken pipe)",
        shell=f"{{py}} simulate {B} {FL} | head -c1 >/dev/null; echo status of rigidid: ${{{{PIPESTATUS[0]}}}} >&2",
        timeout=30,
    )
    case(
        "modes --method xyz",
        shell=f"{{py}} simulate {B} {FL} --records rec -o /dev/stdout >/dev/null 2>&1; "
        f"{{py}} modes {FL} rec/record-1.csv --method xyz",
    )
    case(
        "identify --resample 1000000",
        shell=f"{{py}} simulate {B} {FL} --records rec -o /dev/stdout >/dev/null 2>&1; "
        f"{{py}} identify {FL} rec/record-1.csv rec/record-2.csv --records --resample 1000000",
        timeout=60,
    )
    case(
        "identify --max-order 100000",
        shell=f"{{py}} simulate {B} {FL} --records rec -o /dev/stdout >/dev/null 2>&1; "
        f"{{py}} identify {FL} rec/record-1.csv rec/record-2.csv --records --max-order 100000",
        timeout=60,
    )
    case(
        "modes --n-modes 100",
        shell=f"{{py}} simulate {B} {FL} --records rec -o /dev/stdout >/dev/null 2>&1; "
        f"{{py}} modes {FL} rec/record-1.csv rec/record-2.csv --n-modes 100",
        timeout=120,
    )
    case(
        "records of different sample intervals",
        shell=f"{{py}} simulate {B} {FL} --records r1 -o /dev/stdout "
        f">/dev/null 2>&1; {{py}} simulate {B} {FL} --records r2 --sample-rate 400 -o /dev/stdout >/dev/null 2>&1; "
        f"{{py}} modes {FL} r1/record-1.csv r2/record-1.csv",
        timeout=60,
    )
    case("identify --bogus-option", ["identify", L, M, "--bogus"])
    case(
        "UFF whose second impact misses sensor 1's record",
        ["identify", "t.uff", "--records"],
        setup=lambda d: uff_test(d, drop_sensor=True),
    )
    case("UFF with 5 modes", ["identify", "t.uff"], setup=lambda d: uff_test(d, modes=5))
    case(
        "simulate with a bad body",
        ["simulate", "b.json", FL],
        setup=lambda d: (d / "b.json").write_text(Path(B).read_text().replace('"mass"', '"masss"', 1)),
    )


if __name__ == "__main__":
    main()
