#pragma once
// Task 5, the pixel pendulum: frames of the Gym pendulum scene, an autoencoder with an HNN (or a
// baseline MLP) on its 2-D latent space, trained on `ae + cc + 0.1 hnn`; latent rollouts decoded
// to frames; the energy bump along the Riemann gradient of the learned H. The run folder holds
// the files of every task (metrics.json, loss_curve.csv, params.bin) plus the pixel ones.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <vector>

#include "nn/autoencoder.h"
#include "nn/dynamics.h"
#include "nn/hnn.h"
#include "nn/loss.h"
#include "physics/gym_pendulum.h"
#include "tasks/run.h"
#include "tasks/trainer.h"

namespace hnn::tasks::pixel {

inline constexpr const char* kTaskName = "pixel-pendulum";
inline constexpr int kFramePixels = physics::GymPendulum::kSide * physics::GymPendulum::kSide;
inline constexpr int kPairPixels = 2 * kFramePixels;  // the model's input: two frames

/// Everything that defines a pixel-pendulum run but the model kind and the seed. The defaults
/// are the reference implementation's (tasks.md, task 5); tests use smaller ones.
struct PixelConfig {
  int trials = 200;            // Gym trials, each from sample_gym_state
  int frames_per_trial = 103;  // frames (Gym states) per trial; pairs per trial = this - 3
  double test_fraction = 0.2;  // the first 20% of the pairs (trial-major) are the test split
  int ae_hidden = 200;         // autoencoder widths 1568 -> h -> h -> h -> 2 and back
  std::vector<int> hidden = {200, 200};  // the latent HNN / baseline MLP, tanh
  int steps = 10000;
  int batch_size = 200;  // drawn without replacement each step, as torch.randperm[:200]
  double learning_rate = 1e-3;
  double weight_decay = 1e-5;  // L2 (Adam, PyTorch semantics) on the autoencoder
  /// L2 on the latent HNN / baseline MLP. The reference put 1e-5 on every parameter; here that
  /// kills the latent HNN: its loss gradients (~1e-4 over 40k weights) are about as small as
  /// 1e-5 x weight, and Adam's normalised step then shrinks every weight by ~lr per step, to
  /// 1e-18 within 10,000 steps, after which H is flat and rollouts freeze (measured, seed 0).
  /// Both models get 0 by default; set it to weight_decay for the reference's recipe.
  double dynamics_weight_decay = 0.0;
  double hnn_weight = 0.1;   // loss = ae + cc + hnn_weight * hnn
  int record_every = 0;      // loss-curve interval; 0: about 100 points
  int curve_rows = 1000;     // rows of each split for the loss-curve points
  int rollout_frames = 200;  // frames after the first pair in each latent rollout
  int rollout_trials = 0;    // rollouts from this many test trials; 0: every whole test trial
  double rtol = 1e-9, atol = 1e-12;  // dopri5 tolerances of the latent rollouts

  int pairs_per_trial() const { return frames_per_trial - 3; }
  nlohmann::json to_json() const;
  static PixelConfig from_json(const nlohmann::json& j);
};

/// Throws tasks::Error naming the first bad setting.
void validate(const PixelConfig& config);

/// The task among the others (make_task("pixel-pendulum")): its name, defaults and Table 1 row.
/// Its build_dataset is the reference's generic view (pairs as x, next pair minus pair as dx/dt,
/// about 500 MB in double); the pipeline below uses the 4x smaller frame store instead.
std::unique_ptr<Task> make_pixel_pendulum_task();

/// The frames of every trial (stored once, as float: pairs are assembled when needed) and the
/// Gym state behind each frame. Pair r of trial j is (frame f, frame f + 1) with
/// f = j * frames_per_trial + (r mod pairs) + 1, and its successor starts one frame later: the
/// reference's offsets, 100 usable pairs per trial of 103 frames. Pairs are numbered trial-major
/// and the first test_rows() of them are the test split.
struct PixelData {
  using Frames = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  int trials = 0, frames_per_trial = 0;
  Frames frames;                          // trials * frames_per_trial x 784
  std::vector<physics::GymState> states;  // one per frame
  Eigen::Index test_rows = 0;

  int pairs_per_trial() const { return frames_per_trial - 3; }
  Eigen::Index pairs() const { return Eigen::Index(trials) * pairs_per_trial(); }
  Eigen::Index train_rows() const { return pairs() - test_rows; }
  /// Frame index of the first frame of pair `row`.
  Eigen::Index first_frame(Eigen::Index row) const;
  /// The pairs (next = false) or their successors (next = true) of the given rows: n x 1568.
  template <typename T>
  ad::Matrix<T> pairs_of(const std::vector<Eigen::Index>& rows, bool next) const;
  /// Canonical (theta, p) of each given pair: pair_state of its two frames' true angles.
  physics::Batch coords_of(const std::vector<Eigen::Index>& rows) const;
  /// Whole test trials: the trials all of whose pairs are in the test split (at least one).
  int test_trials() const;
};

/// Deterministic: the same seed gives the same frames, bit for bit.
PixelData build_pixel_data(const PixelConfig& config, std::uint64_t seed);

/// The autoencoder and the latent dynamics model, saved and loaded together. Parameters:
/// "autoencoder.<...>" then "dynamics.<...>"; kind "pixel:<dynamics kind>".
template <typename T>
class PixelModel : public nn::Module<T> {
 public:
  /// Initialised from rng: the autoencoder first, then the latent MLP (the reference's order).
  PixelModel(const PixelConfig& config, nn::ModelKind kind, std::mt19937_64& rng);
  PixelModel(nn::Autoencoder<T> autoencoder, std::unique_ptr<nn::DynamicsModel<T>> dynamics);
  PixelModel(PixelModel&&) noexcept = default;
  PixelModel& operator=(PixelModel&&) noexcept = default;

  ad::Var<T> encode(const ad::Var<T>& x) const { return autoencoder_.encode(x); }
  ad::Var<T> decode(const ad::Var<T>& z) const { return autoencoder_.decode(z); }
  /// Plain values, in chunks, without a graph.
  ad::Matrix<T> encode(const ad::Matrix<T>& x) const;
  ad::Matrix<T> decode(const ad::Matrix<T>& z) const;
  const nn::Autoencoder<T>& autoencoder() const { return autoencoder_; }
  const nn::DynamicsModel<T>& dynamics() const { return *dynamics_; }
  bool is_hnn() const { return dynamics_->config().model == nn::ModelKind::kHnn; }
  /// The learned H at latent states (an HNN only; throws std::logic_error otherwise).
  ad::Matrix<T> energy(const ad::Matrix<T>& z) const;

  void visit_parameters(const nn::ParameterVisitor<T>& visit) override;
  std::string kind() const override { return "pixel:" + dynamics_->kind(); }

  template <typename U>
  PixelModel<U> cast() const {
    return PixelModel<U>(autoencoder_.template cast<U>(), nn::cast_model<U>(*dynamics_));
  }

 private:
  nn::Autoencoder<T> autoencoder_;
  std::unique_ptr<nn::DynamicsModel<T>> dynamics_;
};

/// The per-sample terms of the loss (each R x 1, on the graph): ae = mean over pixels of
/// (x - dec(enc(x)))^2; hnn = mean over the latent of (z' - (z + f(z)))^2 with z' = enc(x_next)
/// (one Euler step of one frame); cc = (z_p - (z'_q - z_q))^2; total = ae + cc + w hnn.
template <typename T>
struct PixelLoss {
  ad::Var<T> total, ae, cc, hnn;
};
template <typename T>
PixelLoss<T> pixel_loss(const PixelModel<T>& model, const ad::Var<T>& x, const ad::Var<T>& x_next,
                        double hnn_weight);

/// Adam on the mean of the total loss over minibatches; the loss curve records the combined
/// loss on the first curve_rows of each split. Throws TrainingDiverged on a non-finite loss.
template <typename T>
TrainResult train_pixel_model(PixelModel<T>& model, const PixelData& data,
                              const PixelConfig& config, std::uint64_t seed,
                              const TrainHooks& hooks = {});

/// mean +- std/sqrt(N) of each loss term over a whole split (test = true: the test split).
struct PixelLossStats {
  nn::MeanStderr total, ae, cc, hnn;
};
PixelLossStats pixel_loss_stats(const PixelModel<double>& model, const PixelData& data, bool test,
                                double hnn_weight);

/// The canonical state (theta, p) of a pair of frames whose Gym angles (from upright) are th_a
/// then th_b: taken halfway between them, theta = th_a + d/2 - pi and p = 0.25 d / dt with
/// d = wrap(th_b - th_a). Gym's semi-implicit Euler step is a leapfrog whose velocities live at
/// half steps, so this state's energy stays within about 0.5% along a true trajectory, where
/// the energy of either frame's own (th, thdot) swings by about 10% each period.
Eigen::RowVector2d pair_state(double th_a, double th_b);
/// pair_state of the angles recovered from a decoded or rendered pair (1568 values), each by
/// GymPendulum::angle_from_frame (the intensity centroid); NaNs for a blank frame.
Eigen::RowVector2d state_from_pair(const physics::GymPendulum& scene,
                                   const Eigen::Ref<const Eigen::RowVectorXd>& pair);
/// pair_state of the angles recovered from two frames (784 values each) one time step apart.
Eigen::RowVector2d state_from_frames(const physics::GymPendulum& scene,
                                     const Eigen::Ref<const Eigen::RowVectorXd>& first,
                                     const Eigen::Ref<const Eigen::RowVectorXd>& second);

/// Latent rollouts from the first pair of each rollout trial (all trials integrated together
/// by dopri5, time unit = one frame), decoded, against the true Gym continuation.
struct PixelRollouts {
  std::vector<double> t;                            // 0, 1, ..., rollout_frames
  std::vector<Eigen::MatrixXd> z;                   // per trajectory: times x 2 latent states
  Eigen::MatrixXd frame_mse;                        // trajectories x times: MSE of the decoded pair
  Eigen::MatrixXd true_theta, true_p, true_energy;  // pair_state of the true angles
  /// pair_state of the angles of the first frames of decoded pairs k and k + 1: the rollout's
  /// own frames over time (Note [Velocity from the rollout's frames], pixel_rollout.cpp).
  Eigen::MatrixXd pred_theta, pred_p, pred_energy;
  Eigen::MatrixXd pair_energy;    // from the two frames of one decoded pair (decoder-biased)
  Eigen::MatrixXd frames_energy;  // recovered from the true frames: the method's floor
  Eigen::MatrixXd learned_h;      // the HNN's H along its latent path (empty otherwise)
  std::vector<bool> failed;
  std::vector<std::string> failures;
  long nfev = 0;
  /// Second frames (times x 784) of the first `keep` trajectories, for GIFs and strips.
  std::vector<Eigen::MatrixXf> true_frames, pred_frames;
};
PixelRollouts pixel_rollouts(const PixelModel<double>& model, const PixelData& data,
                             const PixelConfig& config, int keep = 4);

/// Which recovered energy pixel_energy_mse compares with the true one.
enum class EnergySource {
  kRollout,     // pred_energy: the headline metric
  kWithinPair,  // pair_energy
  kTrueFrames,  // frames_energy: the floor of recovering states from frames
};
/// Energy MSE over trajectories and times with the 5-split standard error of tasks::energy_mse.
nn::MeanStderr pixel_energy_mse(const PixelRollouts& rollouts,
                                EnergySource source = EnergySource::kRollout);

// ---- run folders (tasks/pixel_run.cpp) --------------------------------------------------------

/// `hnn train pixel-pendulum`: the options' steps, batch, hidden, lr, dtype, threads and seed
/// override the config. Writes metrics.json (the keys of every task, plus "pixel"),
/// loss_curve.csv, params.bin, pixel_rollout.csv, latent_grid.csv, latent_paths.csv,
/// rollout.gif and rollout_strip.png.
nlohmann::json run_pixel_training(const RunOptions& options, PixelConfig config = {});

/// A pixel run folder loaded back: its settings, data and model (in double).
struct LoadedPixelRun {
  RunOptions options;
  PixelConfig config;
  PixelData data;
  std::unique_ptr<PixelModel<double>> model;
};
LoadedPixelRun load_pixel_run(const std::filesystem::path& run_dir);
/// True when run_dir/metrics.json names the pixel-pendulum task.
bool is_pixel_run(const std::filesystem::path& run_dir);

/// `hnn evaluate`: the metrics again from params.bin (and, with write_files, the files again).
nlohmann::json evaluate_pixel_run(const std::filesystem::path& run_dir, bool write_files);

/// `hnn rollout` of a pixel run: latent paths with any integrator, decoded states as CSV
/// (source,traj,t,z_q,z_p,theta,p,energy,learned_h).
struct PixelRolloutOptions {
  std::string integrator = "dopri5";
  double dt = 0.25, rtol = 1e-9;
  int frames = 200, trajectories = 5;
  std::filesystem::path out;  // default RUN/pixel_rollout_<integrator>.csv
};
std::filesystem::path write_pixel_rollout(const std::filesystem::path& run_dir,
                                          const PixelRolloutOptions& options);

/// Truth, baseline and HNN side by side: out/rollout.gif (animated, one row per trajectory) and
/// out/rollout_strip.png (every `stride` frames; rows truth, baseline, HNN), like Figure 4.
/// Both runs must have the same data (seed and config).
void write_comparison(const std::filesystem::path& baseline_run,
                      const std::filesystem::path& hnn_run, const std::filesystem::path& out,
                      int trajectories = 2, int stride = 10);

// ---- the energy bump (tasks/pixel_bump.cpp) -------------------------------------------------

/// Figure 5: from an encoded test pair, integrate the symplectic gradient S_H for `before`
/// frames, then the Riemann gradient R_H = (dH/dq, dH/dp) (or -R_H to lower H), then S_H for
/// `after` frames. The learned H grows along R_H at the rate |grad H|^2, which varies a lot over
/// the latent plane, so the bump is given as a rise in H: `raise` times the spread of H over the
/// test trials' first pairs (keeping the bumped swing among the energies the model was trained
/// on), unless a fixed `riemann` time is given.
struct BumpOptions {
  int trajectory =
      -1;  // test trial that starts it; -1: at the 25th percentile of H (75th to lower)
  double before = 60, after = 100;
  double raise = 0.5;         // rise of H as a fraction of its spread (negative: lower H)
  double riemann = 0;         // when non-zero: time along R_H (negative: along -R_H), not `raise`
  double dt = 1;              // output spacing (frames): the GIF runs in real time
  std::filesystem::path out;  // folder; default the run folder
};
struct BumpResult {
  int trajectory = 0;
  double riemann_time = 0;                           // time spent along R_H
  double h_before = 0, h_after = 0;                  // learned H in each S_H phase (mean)
  double energy_before = 0, energy_after = 0;        // true energy recovered from decoded frames
  double amplitude_before = 0, amplitude_after = 0;  // max |theta| of the decoded frames
  std::vector<std::filesystem::path> files;
};
/// Writes bump.csv (phase,t,z_q,z_p,learned_h,theta,p,energy), bump.gif and bump_strip.png.
/// theta, p and energy: state_from_frames of the decoded state and of the state one frame later
/// along S_H.
BumpResult energy_bump(const std::filesystem::path& run_dir, const BumpOptions& options);
BumpResult energy_bump(const PixelModel<double>& model, const PixelData& data,
                       const PixelConfig& config, const BumpOptions& options);

}  // namespace hnn::tasks::pixel
