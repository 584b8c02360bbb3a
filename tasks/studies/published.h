#pragma once
// The published numbers hnn sets beside its own, in one home: data/peers.json. It holds the
// peers' numbers (hnn compare) and the HNN paper's Table 1 (hnn reproduce's table1.md, and hnn
// compare's rows run at a task's defaults), one entry per number.

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "nn/dynamics.h"

namespace hnn::tasks {

/// One published number: its mean and standard error.
struct PaperValue {
  double mean = 0, se = 0;
};
/// The HNN paper's Table 1 row of a task and model.
struct PaperRow {
  PaperValue train_loss, test_loss, energy_mse;
};

/// $HNN_PEERS if set, else the shipped data/peers.json (tasks/data/data_files.h: $HNN_DATA_DIR,
/// the source tree's data/, or the installed share/hnn/data).
std::filesystem::path published_path();

/// The file's content, checked entry by entry; an Error of one line naming the file and the
/// entry otherwise.
nlohmann::json read_published(const std::filesystem::path& file);

/// The HNN paper's Table 1 row of `task` and `model` among read_published's entries; an Error
/// naming the number the file lacks.
PaperRow paper_row(const nlohmann::json& published, const std::string& task, nn::ModelKind model);

}  // namespace hnn::tasks
