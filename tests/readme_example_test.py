#!/usr/bin/env python3
"""The README's library example is docs/examples/session_example.cpp, line for line: the
file is what ctest compiles and runs (session_example), so the README cannot show code that
no longer builds. Usage: readme_example_test.py SOURCE_DIR"""
import pathlib
import sys

root = pathlib.Path(sys.argv[1])
example = (root / "docs/examples/session_example.cpp").read_text()
readme = (root / "README.md").read_text()
marker = "<!-- mgrl-example: docs/examples/session_example.cpp -->\n```cpp\n"
start = readme.find(marker)
if start < 0:
    sys.exit("README.md: expected the library example after '<!-- mgrl-example: docs/examples/session_example.cpp -->' "
             "in a ```cpp block, found no such marker")
start += len(marker)
end = readme.find("```\n", start)
shown = readme[start:end]
if shown != example:
    import difflib
    diff = "".join(difflib.unified_diff(example.splitlines(True), shown.splitlines(True),
                                        "docs/examples/session_example.cpp", "README.md"))
    sys.exit(f"README.md: expected the library example to equal docs/examples/session_example.cpp, found:\n{diff}")
print(f"readme_example: the README's example is docs/examples/session_example.cpp ({example.count(chr(10))} lines)")
