// The framework naming a plug-in folder: the built-in plug-ins are listed above it.
#include "learners/learners.hpp"
