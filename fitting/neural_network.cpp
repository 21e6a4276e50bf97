// Eigen-only PointNet inference and a small .npy reader (see neural_network.h).
#include "fitting/neural_network.h"

#include "geometry/error.h"

#include <cstring>
#include <fstream>
#include <iterator>
#include <utility>

namespace quadrix {
namespace {

/// Value of `key` in a .npy header dict ("{'descr': '<f4', 'fortran_order': False, 'shape': (2, 3), }").
std::string header_value(const std::string& header, const std::string& key, const std::string& path) {
  const std::string quoted = "'" + key + "'";
  const std::size_t at = header.find(quoted);
  if (at == std::string::npos) throw file_error(path, "npy header has no " + quoted + " entry: " + header);
  std::size_t begin = header.find(':', at + quoted.size());
  if (begin == std::string::npos) throw file_error(path, "npy header entry " + quoted + " has no value");
  ++begin;
  while (begin < header.size() && header[begin] == ' ') ++begin;
  std::size_t end = begin;
  if (begin < header.size() && header[begin] == '(') {
    end = header.find(')', begin);
    if (end == std::string::npos) throw file_error(path, "npy header shape is not closed: " + header);
    return header.substr(begin, end - begin + 1);
  }
  if (begin < header.size() && header[begin] == '\'') {
    end = header.find('\'', begin + 1);
    if (end == std::string::npos) throw file_error(path, "npy header string is not closed: " + header);
    return header.substr(begin + 1, end - begin - 1);
  }
  end = header.find_first_of(",}", begin);
  if (end == std::string::npos) throw file_error(path, "npy header entry " + quoted + " is not terminated");
  return header.substr(begin, end - begin);
}

std::vector<std::int64_t> parse_shape(const std::string& text, const std::string& path) {
  std::vector<std::int64_t> shape;
  std::size_t i = 1;  // after '('
  while (i < text.size()) {
    while (i < text.size() && (text[i] == ' ' || text[i] == ',')) ++i;
    if (i >= text.size() || text[i] == ')') break;
    std::size_t used = 0;
    long long value = 0;
    try {
      value = std::stoll(text.substr(i), &used);
    } catch (const std::exception&) {
      throw file_error(path, "npy shape is not a tuple of integers: " + text);
    }
    if (value < 0 || used == 0) throw file_error(path, "npy shape has a negative dimension: " + text);
    shape.push_back(value);
    i += used;
  }
  return shape;
}

}  // namespace

NpyArray read_npy_float32(const std::string& path) {
  std::ifstream stream(path, std::ios::binary);
  if (!stream) throw file_error(path, "cannot open the weight file (missing or unreadable)");
  const std::string bytes((std::istreambuf_iterator<char>(stream)), std::istreambuf_iterator<char>());
  static const char magic[] = "\x93NUMPY";
  if (bytes.size() < 10 || std::memcmp(bytes.data(), magic, 6) != 0)
    throw file_error(path, "not a .npy file (bad magic string)");
  const auto major = static_cast<unsigned char>(bytes[6]);
  std::size_t header_length = 0;
  std::size_t header_start = 0;
  if (major == 1) {
    header_length = static_cast<unsigned char>(bytes[8]) | (static_cast<std::size_t>(static_cast<unsigned char>(bytes[9])) << 8);
    header_start = 10;
  } else if (major == 2 || major == 3) {
    if (bytes.size() < 12) throw file_error(path, "truncated .npy header");
    for (int k = 0; k < 4; ++k)
      header_length |= static_cast<std::size_t>(static_cast<unsigned char>(bytes[8 + k])) << (8 * k);
    header_start = 12;
  } else {
    throw file_error(path, "unsupported .npy format version " + std::to_string(major));
  }
  if (bytes.size() < header_start + header_length) throw file_error(path, "truncated .npy header");
  const std::string header = bytes.substr(header_start, header_length);
  const std::string descr = header_value(header, "descr", path);
  if (descr != "<f4") throw file_error(path, "dtype '" + descr + "' is not little-endian float32 ('<f4')");
  if (header_value(header, "fortran_order", path) != "False")
    throw file_error(path, "array is in Fortran order; C order is required");
  NpyArray array;
  array.shape = parse_shape(header_value(header, "shape", path), path);
  std::size_t count = 1;
  for (const std::int64_t dimension : array.shape) count *= static_cast<std::size_t>(dimension);
  const std::size_t data_start = header_start + header_length;
  const std::size_t available = bytes.size() - data_start;
  if (available != count * sizeof(float))
    throw file_error(path, "data holds " + std::to_string(available) + " bytes but the shape needs " +
                               std::to_string(count * sizeof(float)) + " (truncated or corrupt file)");
  array.values.resize(count);
  if (count > 0) std::memcpy(array.values.data(), bytes.data() + data_start, count * sizeof(float));
  return array;
}

Activation activation_from_name(const std::string& name, const std::string& context) {
  if (name == "relu") return Activation::Relu;
  if (name == "identity") return Activation::Identity;
  throw Error(context + ": unknown activation '" + name + "' (expected relu or identity)");
}

PointNetRegressor::PointNetRegressor(std::string name, std::vector<DenseLayer> shared, std::vector<DenseLayer> head)
    : name_(std::move(name)), shared_(std::move(shared)), head_(std::move(head)) {
  if (shared_.empty() || head_.empty()) throw Error(name_ + ": a PointNet needs at least one shared and one head layer");
  Eigen::Index inputs = 3;
  const auto check = [&](const std::vector<DenseLayer>& layers, const std::string& part) {
    for (std::size_t i = 0; i < layers.size(); ++i) {
      const DenseLayer& layer = layers[i];
      const std::string where = name_ + " " + part + " layer " + std::to_string(i);
      if (layer.weight.cols() != inputs)
        throw Error(where + ": weight has " + std::to_string(layer.weight.cols()) + " inputs, expected " +
                    std::to_string(inputs));
      if (layer.bias.size() != layer.weight.rows())
        throw Error(where + ": bias has " + std::to_string(layer.bias.size()) + " entries, weight has " +
                    std::to_string(layer.weight.rows()) + " outputs");
      inputs = layer.weight.rows();
    }
  };
  check(shared_, "shared");
  check(head_, "head");
}

Eigen::Index PointNetRegressor::output_size() const { return head_.empty() ? 0 : head_.back().weight.rows(); }

std::size_t PointNetRegressor::parameter_count() const {
  std::size_t count = 0;
  for (const auto* layers : {&shared_, &head_})
    for (const DenseLayer& layer : *layers) count += static_cast<std::size_t>(layer.weight.size() + layer.bias.size());
  return count;
}

Eigen::VectorXf PointNetRegressor::forward(const Eigen::Matrix3Xf& points) const {
  if (shared_.empty()) throw Error("PointNetRegressor::forward on an empty network");
  if (points.cols() == 0) throw Error(name_ + ": forward needs at least one point");
  // Shared MLP on all points at once: features (channels x N).
  Eigen::MatrixXf features = points;
  for (const DenseLayer& layer : shared_) {
    Eigen::MatrixXf next = layer.weight * features;
    next.colwise() += layer.bias;
    if (layer.activation == Activation::Relu) next = next.cwiseMax(0.0f);
    features = std::move(next);
  }
  Eigen::VectorXf hidden = features.rowwise().maxCoeff();  // symmetric max-pool over the points
  for (const DenseLayer& layer : head_) {
    Eigen::VectorXf next = layer.weight * hidden + layer.bias;
    if (layer.activation == Activation::Relu) next = next.cwiseMax(0.0f);
    hidden = std::move(next);
  }
  return hidden;
}

}  // namespace quadrix
