#pragma once
// The rows of a training set that each step trains on, from a seeded generator whose state a
// checkpoint saves, so that a resumed run draws what the uninterrupted run would have.

#include <Eigen/Core>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

namespace hnn::tasks {

class RowSampler {
 public:
  enum class Draw {
    kWithReplacement,     // independent uniform rows (the paper's minibatch tasks)
    kWithoutReplacement,  // a fresh partial shuffle per step, as torch.randperm(n)[:batch]
    kEpochs,  // shuffled epochs, as torch's DataLoader(shuffle=True, drop_last=True): each epoch
              // a fresh shuffle, its batches in turn; a remainder short of a batch is left out
  };

  /// Batches of `batch` rows of `rows`. Drawn with replacement, a batch of 0 or of every row is
  /// the full batch, which draws nothing. Throws Error when batch is not in [0, rows].
  RowSampler(Eigen::Index rows, Eigen::Index batch, Draw draw, std::uint64_t seed);

  /// True when every step trains on all rows in order (rows() is then empty).
  bool full() const { return full_; }
  /// Draws the next batch.
  void next();
  /// The current batch's row indices in [0, rows).
  const std::vector<Eigen::Index>& rows() const { return batch_; }
  /// Rows per batch (every row for the full batch).
  Eigen::Index batch_size() const { return full_ ? rows_ : Eigen::Index(batch_.size()); }

  /// The generator's state (and the shuffle's order), as text for a checkpoint.
  std::string state() const;
  /// Restores a state(); throws Error when it is not one of this sampler's.
  void set_state(const std::string& state);

 private:
  Draw draw_;
  Eigen::Index rows_;
  bool full_;
  std::mt19937_64 rng_;
  std::vector<Eigen::Index> batch_, order_;  // order_: the shuffle (without replacement, epochs)
  std::size_t epoch_next_ = 0;               // kEpochs: the first row of order_ not yet drawn
};

}  // namespace hnn::tasks
