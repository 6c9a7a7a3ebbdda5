// A plug-in reaching into another plug-in folder instead of meeting it through a seam.
#include "rewards/uses_graph.hpp"
#include "learners/q_learning_steps.hpp"
