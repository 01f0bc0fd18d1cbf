// Probe of the wings (tests/CMakeLists.txt, layers_are_enforced): the same
// wing may include models/core, below it. Building this must succeed.
#include "models/core/scene.h"
