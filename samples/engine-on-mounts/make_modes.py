"""Regenerate modes.csv of this sample: `python samples/engine-on-mounts/make_modes.py`.

The six rigid-body modes are the exact modes of body.json (as `rigidid simulate`
writes them); two elastic modes of the block (bending and torsion, 85 and 120 Hz)
are added as modes 7 and 8, with shapes no rigid-body motion can produce, so
that `rigidid identify` has to choose the six rigid-body modes itself.
"""

from pathlib import Path

import numpy as np

from rigidid import api
from rigidid.io.atomic import write_text_atomic
from rigidid.io.files import ModeTable, modes_csv_text

HERE = Path(__file__).resolve().parent


def main() -> None:
    rigid = api.simulate(HERE / "body.json", HERE / "layout.json")
    layout = api.load_layout(HERE / "layout.json")
    x = np.array([s.position for s in layout.sensors])
    # Bending: readings grow with the square of x; torsion: sign changes with x * y.
    bending = (x[:, 0] / 300.0) ** 2 - 0.4 + 0.02j
    torsion = np.sign(x[:, 0] * x[:, 1]) * (0.5 + np.abs(x[:, 2]) / 400.0) - 0.01j
    table = ModeTable(
        labels=(*rigid.labels, 7, 8),
        frequency_hz=np.concatenate([rigid.frequency_hz, [85.0, 120.0]]),
        damping_ratio=np.concatenate([rigid.damping_ratio, [0.012, 0.009]]),
        sensor_ids=rigid.sensor_ids,
        shapes=np.hstack([rigid.shapes, bending[:, None], torsion[:, None]]),
    )
    write_text_atomic(HERE / "modes.csv", modes_csv_text(table))


if __name__ == "__main__":
    main()
