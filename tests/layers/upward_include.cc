// Probe of the wings (tests/CMakeLists.txt, layers_are_enforced): a file of
// the fluids wing may not include the bodies wing's header. Building this
// must fail to compile.
#include "models/bodies/bodies.h"
