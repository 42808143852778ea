// TEMPORARY: replaced by the engine-grade scanner (h/scan).
#include "penumbra/scan.hpp"
