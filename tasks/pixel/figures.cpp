// The pixel pendulum's figures: animations (GIF) and strips (PNG) of decoded rollouts, Figure
// 4's comparison of truth, baseline and HNN, and the latent paths and grid of Figure C.1.

#include "tasks/pixel/figures.h"

#include <fmt/format.h>

#include <cmath>

#include "tasks/error.h"
#include "tasks/pixel/rollouts.h"
#include "tasks/report/csv_cell.h"
#include "tasks/report/image_io.h"

namespace hnn::tasks::pixel {

namespace fs = std::filesystem;

namespace {

constexpr int kSide = physics::GymPendulum::kSide;
constexpr int kGap = 2;       // pixels between tiles
constexpr int kGifScale = 3;  // each frame pixel as a 3 x 3 block in the GIF
constexpr int kStripScale = 2;
constexpr int kGifDelay = 5;  // hundredths of a second: Gym's dt, so the GIF runs in real time

}  // namespace

// grid[r][c]: frames (times x 784) shown in tile row r, column c; one GIF image per time.
void write_animation(const fs::path& path,
                     const std::vector<std::vector<const Eigen::MatrixXf*>>& grid) {
  const int rows = int(grid.size()), cols = int(grid.front().size());
  const int tile = kSide * kGifScale + kGap;
  const Eigen::Index times = grid.front().front()->rows();
  std::vector<GrayImage> images;
  for (Eigen::Index k = 0; k < times; ++k) {
    GrayImage image(cols * tile + kGap, rows * tile + kGap, 64);
    for (int r = 0; r < rows; ++r) {
      for (int c = 0; c < cols; ++c) {
        draw_frame(image, kGap + c * tile, kGap + r * tile, grid[r][c]->row(k), kSide, kGifScale,
                   physics::GymPendulum::kIntensity);
      }
    }
    images.push_back(std::move(image));
  }
  write_gif(path, images, kGifDelay);
}

// One row per source, every `stride` frames from 0: Figure 4's strip.
void write_strip(const fs::path& path, const std::vector<const Eigen::MatrixXf*>& rows,
                 int stride) {
  const int tile = kSide * kStripScale + kGap;
  const int cols = int((rows.front()->rows() - 1) / stride) + 1;
  GrayImage image(cols * tile + kGap, int(rows.size()) * tile + kGap, 64);
  for (std::size_t r = 0; r < rows.size(); ++r) {
    for (int c = 0; c < cols; ++c) {
      draw_frame(image, kGap + c * tile, kGap + int(r) * tile, rows[r]->row(c * stride), kSide,
                 kStripScale, physics::GymPendulum::kIntensity);
    }
  }
  write_png(path, image);
}

// The encoded pairs of the test trials (Figure C.1's trajectories) and, over their bounding box
// with a margin, the learned field and H on a grid.
void write_latent_files(const PixelModel<double>& model, const PixelData& data,
                        const RunFolder& folder) {
  const int trials = std::min(data.test_trials(), 10);
  std::vector<Eigen::Index> rows;
  for (Eigen::Index i = 0; i < Eigen::Index(trials) * data.pairs_per_trial(); ++i)
    rows.push_back(i);
  const physics::Batch z = model.encode(data.pairs_of<double>(rows, false));
  const physics::Batch x = data.coords_of(rows);
  std::string paths = "traj,k,z_q,z_p,theta,p\n";
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const auto row = Eigen::Index(i);
    paths += fmt::format("{},{},{:.9g},{:.9g},{:.9g},{:.9g}\n", row / data.pairs_per_trial(),
                         row % data.pairs_per_trial(), z(row, 0), z(row, 1), x(row, 0), x(row, 1));
  }
  folder.write_text("latent_paths.csv", paths);

  constexpr int kGrid = 60;
  const Eigen::RowVector2d lo = z.colwise().minCoeff(), hi = z.colwise().maxCoeff();
  const Eigen::RowVector2d margin = 0.3 * (hi - lo).cwiseMax(1e-3);
  physics::Batch grid(kGrid * kGrid, 2);
  for (int a = 0; a < kGrid; ++a) {
    for (int b = 0; b < kGrid; ++b) {
      grid(a * kGrid + b, 0) =
          lo(0) - margin(0) + (hi(0) - lo(0) + 2 * margin(0)) * a / (kGrid - 1);
      grid(a * kGrid + b, 1) =
          lo(1) - margin(1) + (hi(1) - lo(1) + 2 * margin(1)) * b / (kGrid - 1);
    }
  }
  const physics::Batch f = model.dynamics().field(grid);
  Eigen::VectorXd h;
  if (model.is_hnn()) h = model.energy(grid).col(0);
  std::string csv = "z_q,z_p,learned_h,dz_q,dz_p\n";
  for (Eigen::Index k = 0; k < grid.rows(); ++k) {
    csv += fmt::format("{:.9g},{:.9g},{},{:.9g},{:.9g}\n", grid(k, 0), grid(k, 1),
                       h.size() ? csv_cell(h(k), 9) : "", f(k, 0), f(k, 1));
  }
  folder.write_text("latent_grid.csv", csv);
}

void write_comparison(const PixelParts& base, const PixelParts& hnn, const fs::path& out,
                      int trajectories, int stride) {
  HNN_TASKS_CHECK(base.seed == hnn.seed && base.config.trials == hnn.config.trials &&
                      base.config.frames_per_trial == hnn.config.frames_per_trial,
                  "the baseline and the HNN runs were trained on different data (seed or trials "
                  "differ)");
  HNN_TASKS_CHECK(!base.model.is_hnn() && hnn.model.is_hnn(),
                  "the comparison wants a baseline run and then an HNN run");
  PixelConfig config = hnn.config;
  config.rollout_trials = std::max(1, trajectories);
  const PixelRollouts rb = pixel_rollouts(base.model, base.data, config, trajectories);
  const PixelRollouts rh = pixel_rollouts(hnn.model, hnn.data, config, trajectories);
  HNN_TASKS_CHECK(!rb.true_frames.empty() && rb.pred_frames.size() == rh.pred_frames.size(),
                  "no rollout frames to compare (a rollout failed)");
  fs::create_directories(out);
  std::vector<std::vector<const Eigen::MatrixXf*>> grid;
  for (std::size_t i = 0; i < rh.pred_frames.size(); ++i)
    grid.push_back({&rh.true_frames[i], &rb.pred_frames[i], &rh.pred_frames[i]});
  write_animation(out / "rollout.gif", grid);
  write_strip(out / "rollout_strip.png",
              {&rh.true_frames[0], &rb.pred_frames[0], &rh.pred_frames[0]}, stride);
}

}  // namespace hnn::tasks::pixel
