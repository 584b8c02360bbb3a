#include "tasks/train/sampler.h"

#include <algorithm>
#include <numeric>
#include <sstream>
#include <string_view>

#include "tasks/error.h"

namespace hnn::tasks {

RowSampler::RowSampler(Eigen::Index rows, Eigen::Index batch, Draw draw, std::uint64_t seed)
    : draw_(draw), rows_(rows), rng_(seed) {
  HNN_TASKS_CHECK(rows > 0, "training data is empty");
  HNN_TASKS_CHECK(batch >= 0 && batch <= rows,
                  "batch size {} is out of range: the training set has {} rows", batch, rows);
  full_ = draw == Draw::kWithReplacement && (batch == 0 || batch == rows);
  if (full_) return;
  batch_.resize(std::size_t(batch == 0 ? rows : batch));
  if (draw != Draw::kWithReplacement) {
    order_.resize(std::size_t(rows));
    std::iota(order_.begin(), order_.end(), Eigen::Index(0));
    epoch_next_ = order_.size();  // the first draw starts an epoch
  }
}

void RowSampler::next() {
  if (full_) return;
  if (draw_ == Draw::kEpochs) {
    if (epoch_next_ + batch_.size() > order_.size()) {  // a new epoch: Fisher-Yates
      for (std::size_t i = 0; i + 1 < order_.size(); ++i) {
        std::uniform_int_distribution<std::size_t> pick(i, order_.size() - 1);
        std::swap(order_[i], order_[pick(rng_)]);
      }
      epoch_next_ = 0;
    }
    std::copy_n(order_.begin() + std::ptrdiff_t(epoch_next_), batch_.size(), batch_.begin());
    epoch_next_ += batch_.size();
    return;
  }
  for (std::size_t i = 0; i < batch_.size(); ++i) {
    if (draw_ == Draw::kWithReplacement) {
      batch_[i] = std::uniform_int_distribution<Eigen::Index>(0, rows_ - 1)(rng_);
    } else {  // one step of a Fisher-Yates shuffle
      std::uniform_int_distribution<Eigen::Index> pick(Eigen::Index(i), rows_ - 1);
      std::swap(order_[i], order_[std::size_t(pick(rng_))]);
      batch_[i] = order_[i];
    }
  }
}

namespace {
// An epochs sampler's state starts with this word; the other two keep their older form.
constexpr std::string_view kEpochsTag = "epochs";
}  // namespace

std::string RowSampler::state() const {
  std::ostringstream out;
  if (draw_ == Draw::kEpochs) out << kEpochsTag << ' ';
  out << rng_;
  for (Eigen::Index row : order_) out << ' ' << row;
  if (draw_ == Draw::kEpochs) out << ' ' << epoch_next_;
  return out.str();
}

void RowSampler::set_state(const std::string& state) {
  const bool tagged = state.starts_with(kEpochsTag);
  HNN_TASKS_CHECK(tagged == (draw_ == Draw::kEpochs),
                  "the checkpoint drew its minibatches {}, this run {} (--minibatches; a "
                  "constrained task's runs from before it drew shuffled epochs): resume it with "
                  "the hnn that wrote it, or train it again",
                  tagged ? "as shuffled epochs" : "independently",
                  draw_ == Draw::kEpochs ? "as shuffled epochs" : "independently");
  std::istringstream in(tagged ? state.substr(kEpochsTag.size()) : state);
  in >> rng_;
  for (Eigen::Index& row : order_) in >> row;
  if (draw_ == Draw::kEpochs) {
    in >> epoch_next_;
    HNN_TASKS_CHECK(epoch_next_ <= order_.size(), "the checkpoint's sampler state is corrupt");
  }
  HNN_TASKS_CHECK(!in.fail(), "the checkpoint's sampler state is corrupt");
  in >> std::ws;
  HNN_TASKS_CHECK(in.eof(), "the checkpoint's sampler state is of another sampler");
}

}  // namespace hnn::tasks
