// The learned fitter and the auto policy (see learned_fitter.h; paper §"Quadric Fitting").
//
// Pipeline of one fit: deterministic sample of N points -> normalised frame (centre, unit RMS
// radius, principal axes) -> the type's PointNet -> decode canonical scale and pose in that frame
// -> undo the normalisation -> Q = P^-T C P^-1 via Quadric::from_canonical (Eq. (Q=PCP)).
// The normalisation and decoding mirror fitting/training/synthetic_segments.py and
// train_learned_fitter.py `decode`; the golden test checks the network part against PyTorch.
#include "fitting/learned_fitter.h"

#include "geometry/error.h"

#include <nlohmann/json.hpp>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <utility>

#ifndef QUADRIX_DEFAULT_LEARNED_FITTER_DIR
#error "QUADRIX_DEFAULT_LEARNED_FITTER_DIR must be defined by fitting/CMakeLists.txt"
#endif

namespace quadrix {
namespace {

/// Raw output size of each type's network (synthetic_segments.OUTPUT_SIZES).
Eigen::Index expected_output_size(QuadricType type) {
  switch (type) {
    case QuadricType::Plane: return 4;              // normal (3), offset d
    case QuadricType::Line: return 6;               // direction (3), point (3)
    case QuadricType::Sphere: return 4;             // centre (3), log radius
    case QuadricType::CircularCylinder: return 7;   // axis (3), axis point (3), log radius
    case QuadricType::CircularCone: return 7;       // axis (3), apex (3), log tan(half-angle)
    case QuadricType::Ellipsoid: return 12;         // rotation 6-D, log semi-axes (3), centre (3)
    default: return 0;
  }
}

std::string shape_text(const std::vector<std::int64_t>& shape) {
  std::string text = "(";
  for (std::size_t i = 0; i < shape.size(); ++i) text += (i ? ", " : "") + std::to_string(shape[i]);
  return text + ")";
}

/// Reads a .npy tensor and checks its shape against the manifest's; errors name the .npy file.
NpyArray read_checked_tensor(const std::string& directory, const std::string& file,
                             const std::vector<std::int64_t>& expected_shape, const std::string& manifest_path,
                             const std::string& field) {
  const std::string path = directory + "/" + file;
  NpyArray array = read_npy_float32(path);
  if (array.shape != expected_shape)
    throw file_error(path, "shape " + shape_text(array.shape) + " differs from " + shape_text(expected_shape) +
                               " declared for " + field + " in " + manifest_path);
  return array;
}

/// Field `key` of a JSON object, or an Error naming the manifest and the field path.
const nlohmann::json& required(const nlohmann::json& object, const std::string& key, const std::string& manifest_path,
                               const std::string& where) {
  if (!object.is_object() || !object.contains(key))
    throw file_error(manifest_path, "missing field '" + where + (where.empty() ? "" : ".") + key + "'");
  return object.at(key);
}

std::vector<DenseLayer> read_layers(const nlohmann::json& entries, const std::string& directory,
                                    const std::string& manifest_path, const std::string& where) {
  if (!entries.is_array() || entries.empty())
    throw file_error(manifest_path, "field '" + where + "' must be a non-empty list of layers");
  std::vector<DenseLayer> layers;
  for (std::size_t i = 0; i < entries.size(); ++i) {
    const std::string at = where + "[" + std::to_string(i) + "]";
    const nlohmann::json& entry = entries[i];
    try {
      const auto weight_shape = required(entry, "weight_shape", manifest_path, at).get<std::vector<std::int64_t>>();
      const auto bias_shape = required(entry, "bias_shape", manifest_path, at).get<std::vector<std::int64_t>>();
      if (weight_shape.size() != 2 || bias_shape.size() != 1 || bias_shape[0] != weight_shape[0])
        throw file_error(manifest_path, "field '" + at + "' declares weight " + shape_text(weight_shape) + " and bias " +
                                            shape_text(bias_shape) + "; expected (out, in) and (out)");
      const auto weight_file = required(entry, "weight", manifest_path, at).get<std::string>();
      const auto bias_file = required(entry, "bias", manifest_path, at).get<std::string>();
      const NpyArray weight = read_checked_tensor(directory, weight_file, weight_shape, manifest_path, at + ".weight");
      const NpyArray bias = read_checked_tensor(directory, bias_file, bias_shape, manifest_path, at + ".bias");
      DenseLayer layer;
      layer.weight = Eigen::Map<const Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
          weight.values.data(), weight_shape[0], weight_shape[1]);
      layer.bias = Eigen::Map<const Eigen::VectorXf>(bias.values.data(), bias_shape[0]);
      layer.activation = activation_from_name(required(entry, "activation", manifest_path, at).get<std::string>(),
                                              manifest_path + " field '" + at + ".activation'");
      if (!layer.weight.allFinite() || !layer.bias.allFinite())
        throw file_error(directory + "/" + weight_file, "weights of " + at + " are not all finite");
      layers.push_back(std::move(layer));
    } catch (const nlohmann::json::exception& error) {
      throw file_error(manifest_path, "field '" + at + "' is malformed: " + error.what());
    }
  }
  return layers;
}

/// Unit vector of v, or zero when v vanishes (mirrors the training script's clamped division).
Eigen::Vector3d unit_or_zero(const Eigen::Vector3d& v) {
  const double norm = v.norm();
  return norm > 1e-12 ? Eigen::Vector3d(v / norm) : Eigen::Vector3d::Zero();
}

/// Right-handed orthonormal completion whose column `axis` (0 = a, 2 = c) is `direction`.
Eigen::Matrix3d frame_with_axis(const Eigen::Vector3d& direction, int axis) {
  Eigen::Index smallest = 0;
  direction.cwiseAbs().minCoeff(&smallest);
  const Eigen::Vector3d helper = Eigen::Vector3d::Unit(smallest);
  const Eigen::Vector3d first = (helper - helper.dot(direction) * direction).normalized();
  const Eigen::Vector3d second = direction.cross(first);
  Eigen::Matrix3d rotation;
  if (axis == 0)
    rotation << direction, first, second;  // a x b = d x first = second: det +1
  else
    rotation << first, second, direction;  // first x (d x first) = d: det +1
  return rotation;
}

class LearnedFitter final : public QuadricFitter {
 public:
  explicit LearnedFitter(const LearnedFitterOptions& options)
      : options_(options),
        model_(load_learned_fitter_model(options.model_directory.empty() ? default_learned_fitter_directory()
                                                                         : options.model_directory)) {}

  std::string name() const override { return "learned"; }

  QuadricFit fit(const Eigen::Matrix3Xd& points, const Eigen::Matrix3Xd& /*normals*/, FitTypeHint hint) const override {
    const auto start = std::chrono::steady_clock::now();
    QuadricFit result;
    const QuadricType type = hint.value_or(options_.automatic_type);
    result.type = type;
    const auto finish = [&](QuadricFit& fit) -> QuadricFit& {
      fit.time_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
      return fit;
    };
    const LearnedTypeNetwork* network = model_.find(type);
    if (network == nullptr) {
      std::string trained;
      for (const LearnedTypeNetwork& entry : model_.networks)
        trained += (trained.empty() ? "" : ", ") + quadric_type_name(entry.type);
      result.status = FitStatus::Failed;
      result.message = "the learned fitter has no network for type " + quadric_type_name(type) + " (trained: " + trained +
                       "; weights in " + model_.directory + ")";
      return finish(result);
    }
    if (static_cast<std::size_t>(points.cols()) < minimum_points_for_type(type)) {
      result.status = FitStatus::TooFewPoints;
      result.message = "a " + quadric_type_name(type) + " needs at least " +
                       std::to_string(minimum_points_for_type(type)) + " points, got " + std::to_string(points.cols());
      return finish(result);
    }
    result.statistics = point_statistics(points, kStatisticalScaleFactor);
    const Eigen::Matrix3Xd sampled = learned_fitter_sample(points, model_.num_points);
    const SegmentNormalisation frame = normalise_segment(sampled);
    if (!((sampled.colwise() - frame.center).colwise().squaredNorm().maxCoeff() > 0.0)) {
      result.status = FitStatus::Degenerate;
      result.message = "all sampled points coincide; the learned fitter needs an extended segment";
      return finish(result);
    }
    const Eigen::Matrix3Xf input =
        ((frame.rotation.transpose() * (sampled.colwise() - frame.center)) / frame.scale).cast<float>();
    const Eigen::VectorXf raw = network->network.forward(input);
    const LearnedPrimitive primitive = decode_learned_outputs(type, raw, frame, model_.log_clamp);
    if (primitive.type == QuadricType::Invalid || !primitive.scale.allFinite() ||
        !primitive.pose.matrix().allFinite() || !(primitive.scale.minCoeff() > 0.0)) {
      result.status = FitStatus::Failed;
      result.message = "the " + quadric_type_name(type) + " network produced a degenerate axis or a non-finite output";
      return finish(result);
    }
    result.quadric = Quadric::from_canonical(type, primitive.scale, primitive.pose);  // Eq. (Q=PCP)
    result.status = FitStatus::Ok;
    evaluate_fit(points, result, {}, options_.evaluation);
    return finish(result);
  }

 private:
  LearnedFitterOptions options_;
  LearnedFitterModel model_;
};

class AutoFitter final : public QuadricFitter {
 public:
  explicit AutoFitter(const AutoFitterOptions& options)
      : options_(options),
        learned_(make_learned_fitter(options.learned)),
        statistical_(make_statistical_fitter(options.statistical)) {}

  std::string name() const override { return "auto"; }

  QuadricFit fit(const Eigen::Matrix3Xd& points, const Eigen::Matrix3Xd& normals, FitTypeHint hint) const override {
    const auto start = std::chrono::steady_clock::now();
    const QuadricType type = hint.value_or(options_.learned.automatic_type);
    if (std::find(options_.learned_types.begin(), options_.learned_types.end(), type) == options_.learned_types.end()) {
      QuadricFit chosen = statistical_->fit(points, normals, hint);
      const std::string detail = chosen.message.empty() ? "" : "; statistical: " + chosen.message;
      chosen.message = "auto: statistical fit used (the learned fitter is not tried for " + quadric_type_name(type) +
                       ": it does not beat the statistical fit on held-apart scan segments)" + detail;
      chosen.time_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
      return chosen;
    }
    QuadricFit learned = learned_->fit(points, normals, hint);
    // The policy needs f_p2s even when the caller skips residuals: then it is read on the default subsample.
    if (learned.status == FitStatus::Ok && learned.residual_evaluation == ResidualEvaluation::Skip) {
      const FitEvaluationOptions subsample{ResidualEvaluation::Subsample, FitEvaluationOptions{}.max_points};
      learned.algebraic_distance =
          unit_space_algebraic_distance(points, learned.quadric, residual_sample(points.cols(), subsample));
    }
    const std::string threshold = "delta_p = " + number(options_.delta_p);
    QuadricFit chosen;
    if (learned.status == FitStatus::Ok && learned.algebraic_distance <= options_.delta_p) {
      chosen = std::move(learned);
      chosen.message = "auto: learned fit used (f_p2s = " + number(chosen.algebraic_distance) + " <= " + threshold + ")";
    } else {
      const std::string reason =
          learned.status == FitStatus::Ok
              ? "learned f_p2s = " + number(learned.algebraic_distance) + " > " + threshold
              : "learned fit " + fit_status_name(learned.status) + (learned.message.empty() ? "" : ": " + learned.message);
      chosen = statistical_->fit(points, normals, hint);
      const std::string detail = chosen.message.empty() ? "" : "; statistical: " + chosen.message;
      chosen.message = "auto: statistical fit used (" + reason + ")" + detail;
    }
    chosen.time_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    return chosen;
  }

 private:
  static std::string number(double value) {
    char text[32];
    std::snprintf(text, sizeof(text), "%.4g", value);
    return text;
  }

  AutoFitterOptions options_;
  std::unique_ptr<QuadricFitter> learned_;
  std::unique_ptr<QuadricFitter> statistical_;
};

}  // namespace

std::vector<QuadricType> default_auto_learned_types() {
  // Planes and lines are left to the statistical fit: its least- and largest-variance directions are
  // more accurate on scan segments, and a max-pooled network is pulled by outliers on lines.
  return {QuadricType::Sphere, QuadricType::CircularCylinder, QuadricType::CircularCone, QuadricType::Ellipsoid};
}

std::string default_learned_fitter_directory() {
  const char* variable = std::getenv(kLearnedFitterDirectoryVariable);
  if (variable != nullptr && variable[0] != '\0') return variable;
  return QUADRIX_DEFAULT_LEARNED_FITTER_DIR;
}

const LearnedTypeNetwork* LearnedFitterModel::find(QuadricType type) const {
  for (const LearnedTypeNetwork& entry : networks)
    if (entry.type == type) return &entry;
  return nullptr;
}

LearnedFitterModel load_learned_fitter_model(const std::string& directory) {
  const std::string manifest_path = directory + "/manifest.json";
  std::ifstream stream(manifest_path);
  if (!stream)
    throw file_error(manifest_path, std::string("cannot open the learned fitter manifest (set ") +
                                        kLearnedFitterDirectoryVariable + " or run `make train-fitter`)");
  nlohmann::json manifest;
  try {
    stream >> manifest;
  } catch (const nlohmann::json::exception& error) {
    throw file_error(manifest_path, std::string("invalid JSON: ") + error.what());
  }
  LearnedFitterModel model;
  model.directory = directory;
  try {
    if (required(manifest, "format", manifest_path, "").get<std::string>() != "quadrix-learned-fitter" ||
        required(manifest, "version", manifest_path, "").get<int>() != 1)
      throw file_error(manifest_path, "not a version-1 quadrix-learned-fitter manifest");
    model.num_points = required(manifest, "num_points", manifest_path, "").get<int>();
    if (model.num_points < 1) throw file_error(manifest_path, "field 'num_points' must be positive");
    model.log_clamp = required(manifest, "log_clamp", manifest_path, "").get<double>();
    const auto type_names = required(manifest, "types", manifest_path, "").get<std::vector<std::string>>();
    if (type_names.empty()) throw file_error(manifest_path, "field 'types' lists no network");
    const nlohmann::json& networks = required(manifest, "networks", manifest_path, "");
    for (const std::string& type_name : type_names) {
      QuadricType type = QuadricType::Invalid;
      try {
        type = quadric_type_from_name(type_name);
      } catch (const Error& error) {
        throw file_error(manifest_path, "field 'types': " + std::string(error.what()));
      }
      const Eigen::Index outputs = expected_output_size(type);
      if (outputs == 0) throw file_error(manifest_path, "type '" + type_name + "' has no decoder in this build");
      const std::string where = "networks." + type_name;
      const nlohmann::json& entry = required(networks, type_name, manifest_path, "networks");
      if (required(entry, "pooling", manifest_path, where).get<std::string>() != "max")
        throw file_error(manifest_path, "field '" + where + ".pooling' must be \"max\"");
      LearnedTypeNetwork network;
      network.type = type;
      std::vector<DenseLayer> shared =
          read_layers(required(entry, "shared_mlp", manifest_path, where), directory, manifest_path, where + ".shared_mlp");
      std::vector<DenseLayer> head =
          read_layers(required(entry, "head", manifest_path, where), directory, manifest_path, where + ".head");
      try {
        network.network = PointNetRegressor(type_name, std::move(shared), std::move(head));
      } catch (const Error& error) {
        throw file_error(manifest_path, "layers of '" + where + "' do not chain: " + error.what());
      }
      if (network.network.output_size() != outputs ||
          required(entry, "output_size", manifest_path, where).get<Eigen::Index>() != outputs)
        throw file_error(manifest_path, "network '" + type_name + "' has " + std::to_string(network.network.output_size()) +
                                            " outputs; its decoder needs " + std::to_string(outputs));
      network.golden_inputs_path = directory + "/" + required(entry, "golden_inputs", manifest_path, where).get<std::string>();
      network.golden_outputs_path = directory + "/" + required(entry, "golden_outputs", manifest_path, where).get<std::string>();
      model.networks.push_back(std::move(network));
    }
  } catch (const nlohmann::json::exception& error) {
    throw file_error(manifest_path, std::string("malformed manifest: ") + error.what());
  }
  return model;
}

Eigen::Matrix3Xd learned_fitter_sample(const Eigen::Matrix3Xd& points, int count) {
  const Eigen::Index available = points.cols();
  if (available < 1 || count < 1) throw Error("learned_fitter_sample: needs at least one point and a positive count");
  Eigen::Matrix3Xd sampled(3, count);
  for (Eigen::Index i = 0; i < count; ++i) {
    const Eigen::Index column = available >= count ? (i * available) / count : i % available;
    sampled.col(i) = points.col(column);
  }
  return sampled;
}

SegmentNormalisation normalise_segment(const Eigen::Matrix3Xd& sampled) {
  SegmentNormalisation frame;
  const double count = static_cast<double>(sampled.cols());
  frame.center = sampled.rowwise().mean();
  const Eigen::Matrix3Xd centred = sampled.colwise() - frame.center;
  const double radius = std::sqrt(centred.colwise().squaredNorm().sum() / count);
  frame.scale = radius > 0.0 ? radius : 1.0;
  const Eigen::Matrix3Xd scaled = centred / frame.scale;
  const Eigen::Matrix3d covariance = scaled * scaled.transpose() / count;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
  Eigen::Matrix3d axes;
  axes << solver.eigenvectors().col(2), solver.eigenvectors().col(1), solver.eigenvectors().col(0);  // descending
  for (int column = 0; column < 2; ++column) {
    const double third_moment = (axes.col(column).transpose() * scaled).array().cube().sum();
    if (third_moment < 0.0) axes.col(column) = -axes.col(column);
  }
  axes.col(2) = axes.col(0).cross(axes.col(1));
  frame.rotation = axes;
  return frame;
}

LearnedPrimitive decode_learned_outputs(QuadricType type, const Eigen::VectorXf& raw, const SegmentNormalisation& frame,
                                        double log_clamp) {
  const Eigen::Index outputs = expected_output_size(type);
  if (outputs == 0 || raw.size() != outputs)
    throw Error("decode_learned_outputs: " + quadric_type_name(type) + " expects " + std::to_string(outputs) +
                " raw outputs, got " + std::to_string(raw.size()));
  const Eigen::VectorXd y = raw.cast<double>();
  // Normalised frame -> world: directions d_w = E d, points x_w = c + sigma E x, lengths * sigma.
  const auto to_world_direction = [&](const Eigen::Vector3d& d) -> Eigen::Vector3d { return frame.rotation * d; };
  const auto to_world_point = [&](const Eigen::Vector3d& x) -> Eigen::Vector3d {
    return frame.center + frame.scale * (frame.rotation * x);
  };
  const auto clamped_exp = [&](double log_value) { return std::exp(std::clamp(log_value, -log_clamp, log_clamp)); };
  LearnedPrimitive primitive;
  primitive.type = type;
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  switch (type) {
    case QuadricType::Plane: {  // n . u = d; canonical normal = axis a
      const Eigen::Vector3d normal = unit_or_zero(y.head<3>());
      if (normal.isZero()) return LearnedPrimitive{};
      center = y(3) * normal;
      rotation = frame_with_axis(to_world_direction(normal), 0);
      break;
    }
    case QuadricType::Line:
    case QuadricType::CircularCylinder:
    case QuadricType::CircularCone: {  // canonical axis = axis c
      const Eigen::Vector3d axis = unit_or_zero(y.head<3>());
      if (axis.isZero()) return LearnedPrimitive{};
      const Eigen::Vector3d point = y.segment<3>(3);
      center = type == QuadricType::CircularCone ? point : Eigen::Vector3d(point - point.dot(axis) * axis);
      rotation = frame_with_axis(to_world_direction(axis), 2);
      if (type == QuadricType::CircularCylinder) primitive.scale.head<2>().setConstant(frame.scale * clamped_exp(y(6)));
      if (type == QuadricType::CircularCone) primitive.scale.head<2>().setConstant(clamped_exp(y(6)));  // tan: no unit
      break;
    }
    case QuadricType::Sphere:
      center = y.head<3>();
      primitive.scale.setConstant(frame.scale * clamped_exp(y(3)));
      break;
    case QuadricType::Ellipsoid: {  // 6-D rotation (Gram-Schmidt of two columns), log semi-axes, centre
      const Eigen::Vector3d a = unit_or_zero(y.head<3>());
      const Eigen::Vector3d second = y.segment<3>(3);
      const Eigen::Vector3d b = unit_or_zero(second - a.dot(second) * a);
      if (a.isZero() || b.isZero()) return LearnedPrimitive{};
      Eigen::Matrix3d local;
      local << a, b, a.cross(b);
      rotation = frame.rotation * local;
      for (int k = 0; k < 3; ++k) primitive.scale(k) = frame.scale * clamped_exp(y(6 + k));
      center = y.segment<3>(9);
      break;
    }
    default:
      break;
  }
  primitive.pose.linear() = rotation;
  primitive.pose.translation() = to_world_point(center);
  return primitive;
}

std::unique_ptr<QuadricFitter> make_learned_fitter(const LearnedFitterOptions& options) {
  return std::make_unique<LearnedFitter>(options);
}

std::unique_ptr<QuadricFitter> make_auto_fitter(const AutoFitterOptions& options) {
  return std::make_unique<AutoFitter>(options);
}

}  // namespace quadrix
