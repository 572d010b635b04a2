"""What tests share: fixtures' building blocks and helpers (tests/README.md).

Import helpers from here (or from the modules in `tests/` that re-export them), never
from another test module: a test module's names are its own."""
