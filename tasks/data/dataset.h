#pragma once
// The data of the tasks that learn a field: states and their time derivatives, split into train
// and test (rows are samples).

#include <cstdint>

#include "physics/system.h"

namespace hnn::tasks {

using physics::Batch;

struct Dataset {
  Batch train_x, train_dxdt, test_x, test_dxdt;
};

/// FNV-1a of the training inputs and targets: a resumed run refuses data that changed.
std::uint64_t fingerprint(const Dataset& data);

}  // namespace hnn::tasks
