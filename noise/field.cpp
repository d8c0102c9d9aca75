// Implemented by the preset/field work package.
#include "noise/field.h"
