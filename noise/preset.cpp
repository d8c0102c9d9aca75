// Implemented by the preset/field work package.
#include "noise/preset.h"
