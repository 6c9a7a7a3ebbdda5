// A plug-in reaching past the seam headers into the graph stage.
#include "mgrl/graph/motion_graph.hpp"
