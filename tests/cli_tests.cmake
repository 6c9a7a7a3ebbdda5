# CLI tests: see tests/README.md
