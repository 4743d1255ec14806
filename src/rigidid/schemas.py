"""JSON Schemas of rigidid's JSON files, generated from the pydantic models.

``python -m rigidid.schemas DIR`` writes them to DIR (the repository keeps them
in ``schemas/``; a test fails when they drift from the models).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

from pydantic import BaseModel

from rigidid.models import BodyFile, LayoutFile, MountsFile, ReferencesFile, ResultFile

__all__ = ["SCHEMA_FILES", "schema_texts", "write_schemas"]

SCHEMA_FILES: dict[str, type[BaseModel]] = {
    "layout.schema.json": LayoutFile,
    "body.schema.json": BodyFile,
    "result.schema.json": ResultFile,
    "references.schema.json": ReferencesFile,
    "mounts.schema.json": MountsFile,
}


def schema_texts() -> dict[str, str]:
    """File name -> JSON Schema text (draft 2020-12) for every JSON file rigidid reads or writes."""
    out: dict[str, str] = {}
    for name, model in SCHEMA_FILES.items():
        schema: dict[str, Any] = {
            "$schema": "https://json-schema.org/draft/2020-12/schema",
            "$id": f"rigidid/{name}",
            **model.model_json_schema(),
        }
        out[name] = json.dumps(schema, indent=2, sort_keys=False) + "\n"
    return out


def write_schemas(directory: str | Path) -> list[Path]:
    """Write every schema into `directory`; return the paths written."""
    from rigidid.io.atomic import write_text_atomic

    folder = Path(directory)
    folder.mkdir(parents=True, exist_ok=True)
    written = []
    for name, text in schema_texts().items():
        write_text_atomic(folder / name, text)
        written.append(folder / name)
    return written


if __name__ == "__main__":
    for path in write_schemas(sys.argv[1] if len(sys.argv) > 1 else "schemas"):
        sys.stderr.write(f"wrote {path}\n")
