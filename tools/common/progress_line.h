#pragma once
// Progress lines for training, shared by the training tools.

#include <cstdio>
#include <string>

#include "rl/training_progress.h"

namespace pnp::tools {

void print_progress(std::FILE* out, const std::string& role, const rl::CurvePoint& p);

}  // namespace pnp::tools
