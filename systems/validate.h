// validate() lives in storage/validate.h (every layer uses it, I/O included).
#pragma once
#include "storage/validate.h"
