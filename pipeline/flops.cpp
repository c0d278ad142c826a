#include "pipeline/flops.h"

#include <functional>
#include <numeric>
#include <set>
#include <sstream>
#include <stdexcept>

namespace uavsim::pipeline {
namespace {

using Shape = std::vector<std::int64_t>;

std::string ShapeText(const Shape& s) {
  std::ostringstream out;
  out << "[";
  for (std::size_t i = 0; i < s.size(); ++i) out << (i ? ", " : "") << s[i];
  out << "]";
  return out.str();
}

std::int64_t Elements(const Shape& s) {
  return std::accumulate(s.begin(), s.end(), std::int64_t{1}, std::multiplies<>());
}

[[noreturn]] void Fail(const LayerFlops& l, const std::string& what) {
  throw std::invalid_argument("CountFlops: " + l.name + " (" + l.type + "): " + what);
}

void CheckRank(const LayerFlops& l, std::size_t min_rank, std::size_t max_rank) {
  const std::size_t r = l.input_shape.size();
  if (r < min_rank || r > max_rank)
    Fail(l, "expected an input of " + std::to_string(min_rank) +
                (max_rank > min_rank ? " to " + std::to_string(max_rank) : "") +
                " dimensions, got " + ShapeText(l.input_shape));
}

void CheckSize(const LayerFlops& l, std::int64_t got, std::int64_t want, const char* what) {
  if (got != want)
    Fail(l, "expected " + std::to_string(want) + " " + what + ", got shape " +
                ShapeText(l.input_shape));
}

// Conv1d and Conv2d: out = floor((in + 2 p - d (k - 1) - 1) / s) + 1 per
// spatial axis (LibTorch's definition); 'same' keeps the size (LibTorch
// allows it with stride 1 only), 'valid' is p = 0.
template <std::size_t D, class Options>
void CountConv(const Options& o, LayerFlops& l) {
  CheckRank(l, D + 2, D + 2);
  CheckSize(l, l.input_shape[1], o.in_channels(), "input channels");
  l.output_shape = {l.input_shape[0], o.out_channels()};
  std::int64_t kernel = 1;
  for (std::size_t d = 0; d < D; ++d) {
    const std::int64_t in = l.input_shape[2 + d];
    const std::int64_t k = (*o.kernel_size())[d];
    std::int64_t out = in;
    if (!c10::holds_alternative<torch::enumtype::kSame>(o.padding())) {
      const auto* explicit_padding = c10::get_if<torch::ExpandingArray<D>>(&o.padding());
      const std::int64_t p = explicit_padding ? (**explicit_padding)[d] : 0;
      out = (in + 2 * p - (*o.dilation())[d] * (k - 1) - 1) / (*o.stride())[d] + 1;
    }
    if (out < 1) Fail(l, "the input " + ShapeText(l.input_shape) + " leaves no output");
    l.output_shape.push_back(out);
    kernel *= k;
  }
  const std::int64_t outputs = Elements(l.output_shape);
  l.multiply_adds = outputs * (o.in_channels() / o.groups()) * kernel;
  l.other_ops = o.bias() ? outputs : 0;
}

void CountLayer(const torch::nn::Module& m, LayerFlops& l) {
  if (const auto* conv = m.as<torch::nn::Conv2dImpl>()) {
    l.type = "Conv2d";
    CountConv<2>(conv->options, l);
  } else if (const auto* conv1 = m.as<torch::nn::Conv1dImpl>()) {
    l.type = "Conv1d";
    CountConv<1>(conv1->options, l);
  } else if (const auto* linear = m.as<torch::nn::LinearImpl>()) {
    l.type = "Linear";
    const auto& o = linear->options;
    CheckRank(l, 1, 8);
    CheckSize(l, l.input_shape.back(), o.in_features(), "input features");
    l.output_shape = l.input_shape;
    l.output_shape.back() = o.out_features();
    const std::int64_t rows = Elements(l.input_shape) / o.in_features();
    l.multiply_adds = rows * o.in_features() * o.out_features();
    l.other_ops = o.bias() ? Elements(l.output_shape) : 0;
  } else if (m.as<torch::nn::BatchNorm1dImpl>() || m.as<torch::nn::BatchNorm2dImpl>()) {
    const bool two_d = m.as<torch::nn::BatchNorm2dImpl>() != nullptr;
    l.type = two_d ? "BatchNorm2d" : "BatchNorm1d";
    const std::int64_t features = two_d
                                      ? m.as<torch::nn::BatchNorm2dImpl>()->options.num_features()
                                      : m.as<torch::nn::BatchNorm1dImpl>()->options.num_features();
    if (two_d)
      CheckRank(l, 4, 4);
    else
      CheckRank(l, 2, 3);
    CheckSize(l, l.input_shape[1], features, "channels");
    l.output_shape = l.input_shape;
    // Inference: y = s x + t with s, t per channel from the running statistics.
    l.other_ops = 2 * Elements(l.input_shape);
  } else if (m.as<torch::nn::ReLUImpl>()) {
    l.type = "ReLU";
    l.output_shape = l.input_shape;
    l.other_ops = Elements(l.input_shape);
  } else if (m.as<torch::nn::DropoutImpl>()) {
    l.type = "Dropout";  // the identity in eval mode
    l.output_shape = l.input_shape;
  } else if (const auto* pool = m.as<torch::nn::AdaptiveAvgPool2dImpl>()) {
    l.type = "AdaptiveAvgPool2d";
    CheckRank(l, 4, 4);
    const auto& size = *pool->options.output_size();
    l.output_shape = {l.input_shape[0], l.input_shape[1], size[0].value_or(l.input_shape[2]),
                      size[1].value_or(l.input_shape[3])};
    // Each input element added once, each output divided once.
    l.other_ops = Elements(l.input_shape) + Elements(l.output_shape);
  } else {
    l.type = m.name();
    Fail(l, "no FLOP rule for this layer type");
  }
}

}  // namespace

std::int64_t FlopCount::MultiplyAdds() const {
  std::int64_t n = 0;
  for (const LayerFlops& l : layers) n += l.multiply_adds;
  return n;
}

std::int64_t FlopCount::OtherOps() const {
  std::int64_t n = 0;
  for (const LayerFlops& l : layers) n += l.other_ops;
  return n;
}

FlopCount CountFlops(const torch::nn::Module& module, const Shape& input_shape,
                     const std::map<std::string, Shape>& branch_inputs) {
  FlopCount count;
  std::set<std::string> unused;
  for (const auto& [name, shape] : branch_inputs) unused.insert(name);
  Shape shape = input_shape;
  // include_self = false: the root need not be owned by a shared_ptr.
  for (const auto& item : module.named_modules("", /*include_self=*/false)) {
    const torch::nn::Module& m = *item.value();
    if (!m.children().empty()) continue;  // containers: their leaves follow
    LayerFlops l;
    l.name = item.key();
    if (auto it = branch_inputs.find(l.name); it != branch_inputs.end()) {
      shape = it->second;
      unused.erase(l.name);
    }
    l.input_shape = shape;
    CountLayer(m, l);
    shape = l.output_shape;
    count.layers.push_back(std::move(l));
  }
  if (!unused.empty())
    throw std::invalid_argument("CountFlops: branch input '" + *unused.begin() +
                                "' names no leaf layer of the module");
  return count;
}

}  // namespace uavsim::pipeline
