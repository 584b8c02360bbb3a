// LibTorch side of hnn's comparison harness (bench/compare/README.md): the models, loss and
// loop of torch_step.py in C++, on the same data, initial parameters and minibatch rows
// (Note [Same computation] in compare_common.h). Prints one JSON line like hnn_train_step.

#include <torch/torch.h>

#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "bench/compare/compare_common.h"

namespace {

namespace cmp = hnn::compare;
using nlohmann::json;

constexpr double kHnnWeight = 0.1;

torch::Tensor to_tensor(const cmp::Rows& r, torch::Dtype dtype) {
  return torch::from_blob(const_cast<double*>(r.values.data()), {r.rows, r.cols}, torch::kFloat64)
      .to(dtype);
}

// d_in -> 200 -> 200 -> d_out, tanh, orthogonal weights, no bias on the last layer.
struct MlpImpl : torch::nn::Module {
  torch::nn::Linear l1{nullptr}, l2{nullptr}, l3{nullptr};
  MlpImpl(int64_t d_in, int64_t d_out, int64_t hidden = 200) {
    l1 = register_module("l1", torch::nn::Linear(d_in, hidden));
    l2 = register_module("l2", torch::nn::Linear(hidden, hidden));
    l3 = register_module("l3",
                         torch::nn::Linear(torch::nn::LinearOptions(hidden, d_out).bias(false)));
    torch::NoGradGuard no_grad;
    for (auto* l : {&l1, &l2, &l3}) torch::nn::init::orthogonal_((*l)->weight);
  }
  torch::Tensor forward(const torch::Tensor& x) { return l3(torch::tanh(l2(torch::tanh(l1(x))))); }
};
TORCH_MODULE(Mlp);

// HNN: (dH/dp, -dH/dq) of a scalar MLP; baseline: the MLP's output itself.
struct DynamicsImpl : torch::nn::Module {
  bool hnn;
  int64_t half;
  Mlp mlp{nullptr};
  DynamicsImpl(int64_t dim, bool is_hnn) : hnn(is_hnn), half(dim / 2) {
    mlp = register_module("mlp", Mlp(dim, is_hnn ? 1 : dim));
  }
  torch::Tensor forward(torch::Tensor x, bool create_graph = true) {
    if (!hnn) return mlp(x);
    if (!x.requires_grad()) x = x.detach().requires_grad_(true);
    const torch::Tensor dh =
        torch::autograd::grad({mlp(x).sum()}, {x}, {}, /*retain_graph=*/true, create_graph)[0];
    return torch::cat({dh.slice(1, half), -dh.slice(1, 0, half)}, 1);
  }
};
TORCH_MODULE(Dynamics);

// h = relu(L1 x); h += relu(L2 h); h += relu(L3 h); z = L4 h; the decoder likewise.
struct AutoencoderImpl : torch::nn::Module {
  torch::nn::ModuleList enc, dec;
  AutoencoderImpl(int64_t d_in = 1568, int64_t hidden = 200, int64_t latent = 2) {
    const std::vector<std::pair<int64_t, int64_t>> widths = {
        {d_in, hidden}, {hidden, hidden}, {hidden, hidden}, {hidden, latent}};
    for (const auto& [i, o] : widths) enc->push_back(torch::nn::Linear(i, o));
    for (auto it = widths.rbegin(); it != widths.rend(); ++it)
      dec->push_back(torch::nn::Linear(it->second, it->first));
    enc = register_module("enc", enc);
    dec = register_module("dec", dec);
    torch::NoGradGuard no_grad;
    for (auto* list : {&enc, &dec})
      for (auto& m : **list) torch::nn::init::orthogonal_(m->as<torch::nn::Linear>()->weight);
  }
  static torch::Tensor run(torch::nn::ModuleList& layers, const torch::Tensor& x) {
    auto layer = [&](int i, const torch::Tensor& in) {
      return layers[i]->as<torch::nn::Linear>()->forward(in);
    };
    torch::Tensor h = torch::relu(layer(0, x));
    h = h + torch::relu(layer(1, h));
    h = h + torch::relu(layer(2, h));
    return layer(3, h);
  }
  torch::Tensor encode(const torch::Tensor& x) { return run(enc, x); }
  torch::Tensor decode(const torch::Tensor& z) { return run(dec, z); }
};
TORCH_MODULE(Autoencoder);

// The mean training loss of a batch: the field's MSE, or the pixel task's ae + cc + 0.1 hnn.
struct Model {
  Dynamics dyn{nullptr};
  Autoencoder ae{nullptr};

  torch::Tensor loss(const torch::Tensor& x, const torch::Tensor& target, bool create_graph) {
    if (!ae) return (dyn->forward(x, create_graph) - target).pow(2).mean();
    const torch::Tensor z = ae->encode(x), z_next = ae->encode(target);
    const torch::Tensor l_ae = (ae->decode(z) - x).pow(2).mean(1);
    const torch::Tensor l_hnn = (z_next - (z + dyn->forward(z, create_graph))).pow(2).mean(1);
    const torch::Tensor l_cc = (z.select(1, 1) - (z_next.select(1, 0) - z.select(1, 0))).pow(2);
    return (l_ae + l_cc + kHnnWeight * l_hnn).mean();
  }
  std::vector<torch::Tensor> parameters() const {
    std::vector<torch::Tensor> p = ae ? ae->parameters() : std::vector<torch::Tensor>{};
    for (const torch::Tensor& t : dyn->parameters()) p.push_back(t);
    return p;
  }
};

// hnn's initial parameters (float64, torch layout, hnn's order; manifest in path.json).
void load_init(const Model& model, const std::string& path) {
  std::ifstream manifest_file(path + ".json");
  const json manifest = json::parse(manifest_file);
  std::ifstream in(path, std::ios::binary);
  const std::vector<torch::Tensor> params = model.parameters();
  if (!in || params.size() != manifest.size())
    throw std::runtime_error(path + ": parameter count differs from the model's");
  torch::NoGradGuard no_grad;
  for (std::size_t i = 0; i < params.size(); ++i) {
    const std::vector<int64_t> shape = manifest[i].at("shape").get<std::vector<int64_t>>();
    if (params[i].sizes().vec() != shape)
      throw std::runtime_error(path + ": " + manifest[i].at("name").get<std::string>() +
                               " has another shape");
    torch::Tensor v = torch::empty(shape, torch::kFloat64);
    in.read(reinterpret_cast<char*>(v.data_ptr<double>()), std::streamsize(v.numel() * 8));
    params[i].copy_(v);
  }
  if (!in) throw std::runtime_error("short read from " + path);
}

double mean_loss(Model& model, const torch::Tensor& x, const torch::Tensor& dx) {
  double total = 0;
  for (int64_t s = 0; s < x.size(0); s += 1000) {
    const int64_t e = std::min<int64_t>(x.size(0), s + 1000);
    total += model.loss(x.slice(0, s, e), dx.slice(0, s, e), false).item<double>() * double(e - s);
  }
  return total / double(x.size(0));
}

json run(const cmp::Options& o, const cmp::Data& data) {
  const torch::Dtype dtype = o.dtype == "float64" ? torch::kFloat64 : torch::kFloat32;
  const torch::Tensor x = to_tensor(data.train_x, dtype), dx = to_tensor(data.train_dx, dtype);
  const bool hnn = o.model == "hnn";
  torch::manual_seed(int64_t(o.seed));
  Model model;
  std::vector<torch::optim::OptimizerParamGroup> groups;
  const auto options = [&](double wd) {
    return std::make_unique<torch::optim::AdamOptions>(
        torch::optim::AdamOptions(o.lr).weight_decay(wd));
  };
  if (o.task == "pixel") {
    model.ae = Autoencoder();
    model.ae->to(dtype);
    model.dyn = Dynamics(2, hnn);
    model.dyn->to(dtype);
    groups.emplace_back(model.ae->parameters(), options(o.weight_decay));
    groups.emplace_back(model.dyn->parameters(), options(o.dynamics_weight_decay));
  } else {
    model.dyn = Dynamics(cmp::task_dim(o.task), hnn);
    model.dyn->to(dtype);
    groups.emplace_back(model.dyn->parameters(), options(o.weight_decay));
  }
  if (!o.init.empty()) load_init(model, o.init);
  torch::optim::Adam adam(groups, torch::optim::AdamOptions(o.lr));

  cmp::BatchIndices indices(o.seed, x.size(0));
  const int64_t batch = o.batch;
  torch::Tensor rows = torch::empty({batch}, torch::kLong);
  cmp::StepTimer timer(o.steps, o.warmup, o.window);
  for (int step = 0; step < o.steps; ++step) {
    torch::Tensor xb = x, dxb = dx;
    if (batch > 0) {
      int64_t* r = rows.data_ptr<int64_t>();
      for (int64_t i = 0; i < batch; ++i) r[i] = indices.next();
      xb = x.index_select(0, rows);
      dxb = dx.index_select(0, rows);
    }
    const torch::Tensor loss = model.loss(xb, dxb, true);
    adam.zero_grad();
    loss.backward();
    adam.step();
    timer.tick(step + 1);
  }
  json result = timer.to_json();
  result["train_loss"] = mean_loss(model, x, dx);
  result["test_loss"] =
      mean_loss(model, to_tensor(data.test_x, dtype), to_tensor(data.test_dx, dtype));
  return result;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const cmp::Options o = cmp::parse_options(argc, argv, "libtorch_step");
    if ((o.model != "hnn" && o.model != "baseline") || o.loss != "field" || !o.hidden.empty() ||
        o.activation != "tanh" || o.task == "realpend" || o.task == "dblpend") {
      throw std::invalid_argument(
          "runs the HNN paper's cases only (hnn or baseline, 200-200 tanh, dx/dt loss); the "
          "peers' cases (dhnn, lnn, rollout) are PyTorch's alone (torch_peers.py)");
    }
    if (o.data.empty())
      throw std::invalid_argument("--data is required (hnn_train_step --save-data)");
    at::set_num_threads(o.threads);
    const cmp::Data data = cmp::load_data(o);
    json result = run(o, data);
    cmp::add_run_fields(result, o, "libtorch", data);
    result["version"] = TORCH_VERSION;
    std::printf("%s\n", result.dump().c_str());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "libtorch_step: %s\n", e.what());
    return 1;
  }
}
