"""Readers and writers of every file rigidid reads or writes.

Modules here depend on :mod:`rigidid.core`, :mod:`rigidid.models` and
:mod:`rigidid.errors`, never on the report or the command line:

- :mod:`rigidid.io.files`: layout.json, modes.csv, body.json (pydantic-validated);
- :mod:`rigidid.io.records`: time records (CSV) of impacts;
- :mod:`rigidid.io.uff`: universal files (15/2411, 55, 58, 82, 164) through pyuff;
- :mod:`rigidid.io.atomic`: writers that leave a whole file or none.
"""
