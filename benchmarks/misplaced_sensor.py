"""What a misplaced sensor does to the result, and whether rigidid says so (not a test).

The engine sample (samples/engine-on-mounts: 142 kg, 12 sensors over a
600 x 430 x 330 mm body): modes simulated with the true layout, then identified
with a layout in which ONE sensor is stated 120 mm off along x, y or z (moves
along a sensor's own axis change nothing its readings see: skipped). Shape
noise of 0, 1 % and 3 % of each mode's RMS (seeded).

Columns: sensor, axis moved, noise, CG error (mm), largest principal-moment
error (%), the sensor named by the SensorFitWarning (empty: none). The summary
counts cases named correctly, named wrongly and missed, and false alarms on
the true layout.

Run: ``python benchmarks/misplaced_sensor.py [--seeds 3]``
"""

from __future__ import annotations

import argparse
import warnings
from pathlib import Path

import numpy as np

from rigidid import api
from rigidid.core.simulate import add_noise, body_modes
from rigidid.errors import SensorFitWarning
from rigidid.io import files
from rigidid.io.files import ModeTable

ENGINE = Path(__file__).resolve().parent.parent / "samples" / "engine-on-mounts"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--offset", type=float, default=120.0)
    args = parser.parse_args()
    layout = files.load_layout(ENGINE / "layout.json")
    body = api.body_from_file(files.load_body(ENGINE / "body.json"))
    ids, positions, directions = files.layout_arrays(layout)
    exact = body_modes(body, positions, directions)
    truth_moments = np.linalg.eigvalsh(body.inertia_tensor)
    right = wrong = missed = false_alarms = 0
    print(f"{'sensor':>6} {'axis':>4} {'noise':>5} {'CG err mm':>9} {'moment err %':>12}  named")
    for noise in (0.0, 0.01, 0.03):
        for seed in range(args.seeds if noise else 1):
            modes = add_noise(exact, shape=noise, seed=seed) if noise else exact
            f, z = np.abs(modes.poles) / (2 * np.pi), -modes.poles.real / np.abs(modes.poles)
            table = ModeTable(tuple(range(1, 7)), f, z, ids, modes.shapes)
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                api.identify(layout, table)
            false_alarms += any(issubclass(w.category, SensorFitWarning) for w in caught)
            for i, sid in enumerate(ids):
                for axis in range(3):
                    if abs(directions[i, axis]) > 0.99:
                        continue
                    data = layout.model_dump()
                    data["sensors"][i]["position"] = list(data["sensors"][i]["position"])
                    data["sensors"][i]["position"][axis] += args.offset
                    moved = type(layout).model_validate(data)
                    with warnings.catch_warnings(record=True) as caught:
                        warnings.simplefilter("always")
                        result = api.identify(moved, table)
                    named = [str(w.message).split("'")[1] for w in caught if issubclass(w.category, SensorFitWarning)]
                    ident = result.identification
                    cg = float(np.linalg.norm(ident.center_of_gravity - body.center_of_gravity))
                    assert ident.principal_moments is not None
                    moment = float(np.max(np.abs(ident.principal_moments / truth_moments - 1.0))) * 100
                    right += named == [sid]
                    wrong += bool(named) and named != [sid]
                    missed += not named
                    if seed == 0:
                        print(f"{sid:>6} {'xyz'[axis]:>4} {noise:5.2f} {cg:9.1f} {moment:12.1f}  {' '.join(named)}")
    print(f"named correctly {right}, wrongly {wrong}, missed {missed}; false alarms on the true layout {false_alarms}")


if __name__ == "__main__":
    main()
