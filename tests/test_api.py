"""The Python API: what `import rigidid` offers, typed and documented."""

from __future__ import annotations

import inspect

import pytest

import rigidid

PUBLIC = [name for name in rigidid.__all__ if not name.startswith("_")]


@pytest.mark.parametrize("name", PUBLIC)
def test_every_public_name_resolves_and_is_documented(name: str) -> None:
    value = getattr(rigidid, name)
    assert inspect.getdoc(value), name


@pytest.mark.parametrize("name", [n for n in PUBLIC if inspect.isfunction(getattr(rigidid, n))])
def test_functions_document_every_parameter(name: str) -> None:
    func = getattr(rigidid, name)
    doc = inspect.getdoc(func) or ""
    signature = inspect.signature(func)
    assert signature.return_annotation is not inspect.Signature.empty, name
    if len(doc.splitlines()) > 3:  # one-line wrappers point to the documented function
        for parameter in signature.parameters:
            assert parameter in doc, f"{name}: parameter {parameter!r} undocumented"


def test_unknown_name_is_an_attribute_error() -> None:
    with pytest.raises(AttributeError):
        rigidid.no_such_thing  # noqa: B018


def test_errors_are_value_errors() -> None:
    assert issubclass(rigidid.InputError, rigidid.RigididError)
    assert issubclass(rigidid.InputError, ValueError)
    assert issubclass(rigidid.IdentificationError, ValueError)
