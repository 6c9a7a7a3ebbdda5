#pragma once
// A header beside the command line: the benchmark below must not include it.
