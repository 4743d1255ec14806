"""Run the hostile cases of issues 10 and 24 and print what each does.

    python benchmarks/hostile.py [--issue 10|24]

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


E = ROOT / "samples" / "engine-test"


def _copy(d: Path, name: str, data: bytes) -> None:
    (d / name).write_bytes(data)


def _npz(d: Path, name: str = "r.npz", **arrays: object) -> None:
    import numpy as np

    z = np.load(E / "hit1.npz")
    fields = {"data": z["data"], "channels": z["channels"], "dt": z["dt"], **arrays}
    np.savez(d / name, **fields)


def _flip(data: bytes, at: int) -> bytes:
    return data[:at] + bytes([data[at] ^ 0xFF]) + data[at + 1 :]


def _lying_npz(data: bytes) -> bytes:
    import struct

    zz = bytearray(data)
    at = zz.rfind(b"PK\x01\x02")  # the last member's central directory entry: its uncompressed size
    struct.pack_into("<I", zz, at + 24, struct.unpack_from("<I", zz, at + 24)[0] + 800)
    return bytes(zz)


def _huge_npz(d: Path) -> None:
    import io
    import zipfile

    import numpy as np

    z = np.load(E / "hit1.npz")
    with zipfile.ZipFile(d / "r.npz", "w") as zf:
        head = io.BytesIO()
        np.lib.format.write_array_header_1_0(head, {"descr": "<f8", "fortran_order": False, "shape": (10**11, 12)})
        zf.writestr("data.npy", head.getvalue() + bytes(800))
        for key in ("dt", "channels"):
            item = io.BytesIO()
            np.save(item, z[key])
            zf.writestr(f"{key}.npy", item.getvalue())


def _uff_direction(d: Path, code: int) -> None:
    lines = (E / "frf.uff").read_bytes().split(b"\n")
    k = next(i for i, line in enumerate(lines) if line.strip() in (b"58", b"58b") or line.startswith(b"    58b")) + 6
    lines[k] = lines[k][:51] + f"{code:4d}".encode() + lines[k][55:]  # record 6: the response direction
    (d / "f.uff").write_bytes(b"\n".join(lines))


def _h5_link(d: Path, external: bool) -> None:
    import h5py
    import numpy as np

    z = np.load(E / "hit1.npz")
    with h5py.File(d / "r.h5", "w") as fh:
        fh["channels"] = np.array([str(c) for c in z["channels"]], dtype="S")
        fh.attrs["dt"] = float(z["dt"])
        fh["data"] = h5py.ExternalLink("missing.h5", "/data") if external else h5py.SoftLink("/nowhere")


def _wav(d: Path, channels: int = 12, flip_format: bool = False) -> None:
    import numpy as np
    from scipy.io import wavfile

    z = np.load(E / "hit1.npz")
    wavfile.write(d / "r.wav", 3000, np.ascontiguousarray(z["data"][:, :channels]))
    raw = (d / "r.wav").read_bytes()
    if flip_format:
        raw = raw[:20] + b"\x06\x00" + raw[22:]  # the format field: 6, a code scipy maps to no type
    if channels == 0:
        raw = raw[:22] + b"\x00\x00" + raw[24:]
    (d / "r.wav").write_bytes(raw)


def _json(d: Path, name: str, src: Path, edit) -> None:
    import json

    doc = json.loads(src.read_text())
    edit(doc)
    (d / name).write_text(json.dumps(doc))


def _frf_csv(d: Path, edit) -> None:
    lines = (E / "frf.csv").read_text().splitlines()
    (d / "f.csv").write_text("\n".join(edit(lines)) + "\n")


def _negated(lines: list[str]) -> list[str]:
    out = [lines[0]]
    for line in lines[1:]:
        f, r, q, re, im = line.split(",")
        out.append(",".join([f, r, q, repr(-float(re)), repr(-float(im))]))
    return out


def _scaled_hits(d: Path, factor: float) -> None:
    import numpy as np

    for name in ("hit1", "hit2"):
        z = np.load(E / f"{name}.npz")
        np.savez(d / f"{name}.npz", data=z["data"] * factor, channels=z["channels"], dt=z["dt"])


def _uff_512(d: Path) -> None:
    import json

    import numpy as np

    from rigidid.io.uff import write_uff_test

    layout = json.loads((S / "layout.json").read_text())
    ids = [x["id"] for x in layout["sensors"]]
    t = np.arange(1024) / 512.0
    write_uff_test(d / "t.uff", layout, [(t, np.exp(-t)[:, None] * np.ones((1, len(ids))), ids)])


def _cg_and_inertia(d: Path) -> str:
    import json

    if not (d / "o.json").exists():
        return listing(d)
    doc = json.loads((d / "o.json").read_text())
    cg = ", ".join(f"{x:.12g}" for x in doc["center_of_gravity"])
    return f"CG ({cg}), I_xx {doc['inertia_tensor'][0][0]:.12g}"


def issue24() -> None:
    """The causes of issue 24 (hostile input, round two), one case each, in the issue's order."""
    EL, FRF, REFS = str(E / "layout.json"), str(E / "frf.csv"), str(E / "refs.json")
    L, M, FL = str(S / "layout.json"), str(S / "modes.csv"), str(F / "layout.json")
    hit = (E / "hit1.npz").read_bytes()
    frf = ["--frf", "f.uff", "--references", REFS]
    print("## Tracebacks")
    case(".npz not a zip", ["modes", EL, "r.npz"], setup=lambda d: _copy(d, "r.npz", b"not a zip at all" * 40))
    for cut in (0.3, 0.7, 0.98):
        case(f".npz truncated at {cut:.0%}", ["modes", EL, "r.npz"],
             setup=lambda d, c=cut: _copy(d, "r.npz", hit[: int(c * len(hit))]))  # fmt: skip
    case(".npz one byte flipped (bad CRC)", ["modes", EL, "r.npz"],
         setup=lambda d: _copy(d, "r.npz", _flip(hit, len(hit) // 2)))  # fmt: skip
    case(
        ".npz member header claiming a huge array",
        ["modes", EL, "r.npz"],
        setup=_huge_npz,
    )
    case(".h5 data a soft link to nowhere", ["modes", EL, "r.h5"], setup=lambda d: _h5_link(d, False))
    case(".h5 data an external link to a missing file", ["modes", EL, "r.h5"], setup=lambda d: _h5_link(d, True))
    case(".wav format field flipped", ["modes", EL, "r.wav"], setup=lambda d: _wav(d, flip_format=True))
    for code in ("4", "7"):
        for cmd in (["identify", EL, *frf, "--method", "massline"], ["modes", EL, *frf]):
            case(f"UFF 58 FRF response direction {code} ({cmd[0]})", cmd,
                 setup=lambda d, c=code: _uff_direction(d, int(c)))  # fmt: skip
    tiny = [[1e-200, 0, 0], [0, 1e-200, 0], [0, 0, 1e-200]]
    case(
        "mounts.json axes rows of 1e-200",
        ["plan", EL, "--mounts", "m.json"],
        setup=lambda d: _json(d, "m.json", E / "mounts.json", lambda doc: [m.update(axes=tiny) for m in doc["mounts"]]),
    )
    print("## Partial outputs and wrong exits")
    case(
        "identify --json out.json > /dev/full",
        shell=f"{{py}} identify {L} {M} --json out.json > /dev/full",
        check=listing,
    )
    case("identify --csv DIR > /dev/full", shell=f"{{py}} identify {L} {M} --csv out > /dev/full", check=listing)
    case("--mass 1e-320", ["identify", L, M, "--mass", "1e-320", "--json", "o.json"], check=listing)
    case("plan --references, one reference", ["plan", EL, "--references", "r.json", "--json", "o.json"],
         setup=lambda d: _json(d, "r.json", E / "refs.json", lambda doc: doc.update(references=doc["references"][:1])),
         check=listing)  # fmt: skip
    case("truncated UFF", ["identify", "t.uff", "--json", "o.json"],
         setup=lambda d: _copy(d, "t.uff", (E / "test.uff").read_bytes()[:-5000]), check=listing)  # fmt: skip
    case(
        "layout with a sensor deleted",
        ["identify", "lay.json", str(E / "modes.csv"), "--json", "o.json"],
        setup=lambda d: _json(d, "lay.json", E / "layout.json", lambda doc: doc["sensors"].pop()),
        check=listing,
    )
    case("identify --json - >&- (closed stdout)", shell=f"{{py}} identify {L} {M} --json - >&-")
    case("identify --frf --json - >&- (closed stdout)",
         shell=f"{{py}} identify {EL} --frf {FRF} --references {REFS} --method massline --json - >&-")  # fmt: skip
    case("modes --frf --max-order 1001", ["modes", EL, "--frf", FRF, "--references", REFS, "--max-order", "1001"])
    for noise in ("inf", "1e308"):
        case(f"simulate --add-frf-noise {noise}", ["simulate", str(E / "body.json"), EL, "--write-frf", "f.csv",
             "--references", REFS, "--add-frf-noise", noise], check=listing)  # fmt: skip
    print("## Inputs accepted that the contract says are invalid")
    import numpy as np

    case("complex values in .npz", ["modes", EL, "r.npz"],
         setup=lambda d: _npz(d, data=np.load(E / "hit1.npz")["data"] * (1 + 1j)))  # fmt: skip
    case("complex values in .npy", ["modes", EL, "r.npy"],
         setup=lambda d: np.save(d / "r.npy", np.ones((100, 13)) * (1 + 1j)))  # fmt: skip
    case(
        ".npz zip entry size field lying",
        ["modes", EL, "r.npz"],
        setup=lambda d: _copy(d, "r.npz", _lying_npz(hit)),
    )
    case(
        "records CSV with a ragged row",
        ["modes", EL, "h.csv"],
        setup=lambda d: _copy(
            d, "h.csv", (E / "hit1.csv").read_bytes().replace(b"\n", b",1\n", 5).replace(b",1\n", b"\n", 4)
        ),
    )
    case(
        "records CSV cell 1_0",
        ["modes", EL, "h.csv"],
        setup=lambda d: _copy(d, "h.csv", (E / "hit1.csv").read_bytes().replace(b"\n-0.1,", b"\n-0.1_0,", 1)),
    )
    case(
        "FRF CSV cell 1_0",
        ["modes", EL, "--frf", "f.csv", "--references", REFS],
        setup=lambda d: _frf_csv(d, lambda ls: [ls[0], ls[1].replace("0.5,", "0_5,", 1), *ls[2:]]),
    )
    case(
        "FRF CSV full-width digits",
        ["modes", EL, "--frf", "f.csv", "--references", REFS],
        setup=lambda d: _frf_csv(d, lambda ls: [ls[0], ls[1].replace("0.5,", "\uff10.\uff15,", 1), *ls[2:]]),
    )
    case(
        "UFF 58 response direction 0",
        ["modes", EL, *frf],
        setup=lambda d: _uff_direction(d, 0),
    )
    case(
        "mounts.json duplicate ids",
        ["plan", EL, "--mounts", "m.json"],
        setup=lambda d: _json(
            d, "m.json", E / "mounts.json", lambda doc: doc["mounts"][1].update(id=doc["mounts"][0]["id"])
        ),
    )
    case(
        "mounts.json axes not orthogonal",
        ["plan", EL, "--mounts", "m.json"],
        setup=lambda d: _json(
            d,
            "m.json",
            E / "mounts.json",
            lambda doc: doc["mounts"][0].update(axes=[[1, 0, 0], [1, 0.1, 0], [0, 0, 1]]),
        ),
    )
    case(
        "mounts.json in m beside a layout in mm",
        ["plan", EL, "--mounts", "m.json"],
        setup=lambda d: _json(d, "m.json", E / "mounts.json", lambda doc: doc["units"].update(length="m")),
    )
    case(
        "--frf and --records together",
        ["identify", EL, str(E / "hit1.npz"), "--records", "--frf", FRF, "--references", REFS],
    )
    case(
        "massline --band -5 200",
        ["identify", EL, "--frf", FRF, "--references", REFS, "--method", "massline", "--band", "-5", "200"],
    )
    case("--units on a JSON layout", ["identify", L, M, "--units", "m,kg"])
    for opt in (
        ["identify", L, M, "--csv"],
        ["simulate", str(F / "body.json"), FL, "--write-records"],
        ["report", L, M, "-o", "r.html", "--png"],
        ["convert", str(E / "test.uff"), "-o"],
        ["identify", L, M, "--uff"],
    ):
        for target in ("''", "x/"):
            case(f"{' '.join(opt[:1] + opt[-1:])} {target}", [*opt, target], check=listing, timeout=60)
    print("## Neutral changes")
    case("UFF with a byte-order mark", ["identify", "t.uff"],
         setup=lambda d: _copy(d, "t.uff", b"\xef\xbb\xbf" + (E / "test.uff").read_bytes()))  # fmt: skip
    for factor in ("1", "1e300", "1e-300"):
        case(
            f"records scaled by {factor} (engine-test hits)",
            ["identify", EL, "--records", "hit1.npz", "hit2.npz", "--json", "o.json"],
            setup=lambda d, f=factor: _scaled_hits(d, float(f)),
            check=_cg_and_inertia,
            timeout=120,
        )
    print("## Messages")
    case("FRFs all negated", ["identify", EL, "--frf", "f.csv", "--references", REFS, "--method", "massline"],
         setup=lambda d: _frf_csv(d, _negated))  # fmt: skip
    case(
        "FRFs all zero",
        ["identify", EL, "--frf", "f.csv", "--references", REFS, "--method", "massline"],
        setup=lambda d: _frf_csv(d, lambda ls: [ls[0], *[",".join([*x.split(",")[:3], "0", "0"]) for x in ls[1:]]]),
    )
    case(".wav with 0 channels", ["modes", EL, "r.wav"], setup=lambda d: _wav(d, channels=0))
    case("records --max-order 1", ["modes", EL, str(E / "hit1.npz"), "--max-order", "1"])
    case("FRF --max-order 1", ["modes", EL, "--frf", FRF, "--references", REFS, "--max-order", "1"])
    case("FRF --band 600 300", ["modes", EL, "--frf", FRF, "--references", REFS, "--band", "600", "300"])
    case("--n-modes 0 (named by its option)", ["modes", EL, str(E / "hit1.npz"), "--n-modes", "0"])
    case(
        "convert --records-format xyz",
        ["convert", str(E / "test.uff"), "-o", "out", "--records-format", "xyz"],
        check=listing,
    )
    case(
        "simulate --add-frequency-noise 10",
        ["simulate", str(F / "body.json"), FL, "--add-frequency-noise", "10", "--seed", "1"],
    )
    case("--decimate 100", ["modes", EL, str(E / "hit1.npz"), "--decimate", "100"])
    case(
        "simulate --pretrigger 1e7",
        ["simulate", str(F / "body.json"), FL, "--write-records", "r", "--pretrigger", "1e7"],
        check=listing,
    )
    case("--band nan", ["modes", EL, str(E / "hit1.npz"), "--band", "nan", "20"])
    case(
        "plan --references unusable (exit-1 verdict names the file)",
        ["plan", EL, "--references", "r.json"],
        setup=lambda d: _json(d, "r.json", E / "refs.json", lambda doc: doc.update(references=doc["references"][:1])),
    )
    case(
        "a .npy header numpy cannot parse (a library's lines are joined: tests/test_hostile.py)",
        ["modes", EL, "r.npy"],
        setup=lambda d: _copy(
            d,
            "r.npy",
            b"\x93NUMPY\x01\x00v\x00{'descr': '<f8', 'fortran_order': False, 'shape': (3" + b" " * 60 + b"\n",
        ),
    )
    case("npTDMS warnings (a .tdms without its index)", ["modes", EL, "r.tdms"],
         setup=lambda d: _copy(d, "r.tdms", b"TDSm" + bytes(40)))  # fmt: skip
    case(
        "simulate --mounts with two mounts",
        ["simulate", str(F / "body.json"), FL, "--mounts", "m.json"],
        setup=lambda d: _json(d, "m.json", F / "mounts.json", lambda doc: doc.update(mounts=doc["mounts"][:2])),
    )
    case(
        "plan of a one-sensor layout --add 2",
        ["plan", "lay.json", "--body", str(E / "body.json"), "--add", "2"],
        setup=lambda d: _json(d, "lay.json", E / "layout.json", lambda doc: doc.update(sensors=doc["sensors"][:1])),
    )
    case("convert --records-format wav of a 512 Hz UFF", ["convert", "t.uff", "-o", "out", "--records-format", "wav"],
         setup=_uff_512, check=listing)  # fmt: skip
    case(
        "layout unit 'furlong'",
        ["identify", "lay.json", M],
        setup=lambda d: _json(d, "lay.json", S / "layout.json", lambda doc: doc["units"].update(length="furlong")),
    )
    print("## Slow but finishing: see benchmarks/plan_scaling.py and benchmarks/h5_memory.py")


if __name__ == "__main__":
    import argparse

    parser = argparse.ArgumentParser(description="the hostile cases of issues 10 and 24")
    parser.add_argument("--issue", choices=("10", "24", "all"), default="all")
    chosen = parser.parse_args().issue
    if chosen in ("10", "all"):
        main()
    if chosen in ("24", "all"):
        issue24()
