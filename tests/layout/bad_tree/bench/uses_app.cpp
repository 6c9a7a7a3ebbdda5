// A benchmark reaching into a command of the command line and into a plug-in folder.
#include "app/app_command.hpp"
#include "app_command.hpp"
#include "learners/learners.hpp"
