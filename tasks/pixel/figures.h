#pragma once
// The pixel pendulum's figures: animations (GIF) and strips (PNG) of frames, Figure 4's truth /
// baseline / HNN comparison, and the latent paths and grid of Figure C.1 (CSV).

#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <vector>

#include "tasks/pixel/model.h"
#include "tasks/report/run_folder.h"

namespace hnn::tasks::pixel {

/// grid[r][c]: frames (times x 784) shown in tile row r, column c; one GIF image per time.
void write_animation(const std::filesystem::path& path,
                     const std::vector<std::vector<const Eigen::MatrixXf*>>& grid);
/// One row per source, every `stride` frames from 0: Figure 4's strip.
void write_strip(const std::filesystem::path& path, const std::vector<const Eigen::MatrixXf*>& rows,
                 int stride);

/// latent_paths.csv (the encoded pairs of the test trials) and latent_grid.csv (the learned
/// field and H on a grid over their bounding box with a margin).
void write_latent_files(const PixelModel<double>& model, const PixelData& data,
                        const RunFolder& folder);

/// A trained pixel-pendulum run's parts.
struct PixelParts {
  const PixelConfig& config;
  const PixelData& data;
  const PixelModel<double>& model;
  std::uint64_t seed;
};

/// Truth, baseline and HNN side by side: out/rollout.gif (animated, one row per trajectory) and
/// out/rollout_strip.png (every `stride` frames; rows truth, baseline, HNN), like Figure 4.
/// Both runs must have the same data (seed and config).
void write_comparison(const PixelParts& baseline, const PixelParts& hnn,
                      const std::filesystem::path& out, int trajectories = 2, int stride = 10);

}  // namespace hnn::tasks::pixel
