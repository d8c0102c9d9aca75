// Implemented by the mesh work package (see noise/mesh.h).
#include "noise/mesh.h"
