// Minimal Eigen-only inference for the learned fitter (paper §"Quadric Fitting", QuadricsNet-style):
// a float32 .npy reader and a PointNet regressor (shared per-point MLP, max-pool, MLP head).
// No ONNX runtime and no libtorch: weights come from fitting/training/train_learned_fitter.py.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <string>
#include <vector>

namespace quadrix {

/// A float32 array read from a .npy file (row-major values, C order).
struct NpyArray {
  std::vector<std::int64_t> shape;  ///< dimensions, outermost first
  std::vector<float> values;        ///< product(shape) values in C order
};

/// Reads a NumPy .npy file (format 1.0/2.0/3.0) holding little-endian float32 ('<f4') in C order.
/// Throws quadrix::Error "<path>: <what was wrong>" for a missing file, bad magic, unsupported dtype
/// or order, a malformed header, or fewer data bytes than the shape needs.
NpyArray read_npy_float32(const std::string& path);

/// Element-wise activation after a dense layer.
enum class Activation {
  Identity,  ///< y = x
  Relu,      ///< y = max(x, 0)
};

/// Parses "identity" or "relu"; throws quadrix::Error naming `context` and the text otherwise.
Activation activation_from_name(const std::string& name, const std::string& context);

/// One dense layer y = act(W x + b) with W (outputs x inputs), as torch.nn.Linear stores it.
struct DenseLayer {
  Eigen::MatrixXf weight;         ///< W, outputs x inputs
  Eigen::VectorXf bias;           ///< b, outputs
  Activation activation = Activation::Relu;  ///< applied after W x + b
};

/// PointNet regressor: every point goes through the shared MLP, the features are max-pooled over
/// the points, and the head MLP maps the pooled feature to the outputs. Immutable after construction,
/// so one instance may be used from several threads.
class PointNetRegressor {
 public:
  /// An empty regressor (input_size() == 0); forward() on it throws quadrix::Error.
  PointNetRegressor() = default;
  /// Checks that the layers chain (each layer's inputs = previous outputs, biases match, the first
  /// shared layer takes 3 inputs); throws quadrix::Error naming `name` and the layer otherwise.
  PointNetRegressor(std::string name, std::vector<DenseLayer> shared, std::vector<DenseLayer> head);

  /// Raw outputs for one segment given as 3 x N float points in the network's input frame.
  Eigen::VectorXf forward(const Eigen::Matrix3Xf& points) const;

  /// Network name used in error messages (e.g. "plane").
  const std::string& name() const { return name_; }
  /// Number of raw outputs.
  Eigen::Index output_size() const;
  /// Number of learned parameters (weights + biases).
  std::size_t parameter_count() const;

 private:
  std::string name_;
  std::vector<DenseLayer> shared_;
  std::vector<DenseLayer> head_;
};

}  // namespace quadrix
