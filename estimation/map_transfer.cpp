// Bytes of what a map run's workers return (mapping.h): a scan's model (MappedScan) and a pair's
// edge (MapEdge), so that modelling and registration can run in other processes or machines and the
// coordinator rebuilds exactly what it would have computed itself. Models use the binary scene-model
// format (fitting/scene_model.h); numbers are stored as their IEEE-754 bytes, little-endian, so a
// round trip is exact.
#include "estimation/mapping.h"

#include "geometry/error.h"

#include <cstdint>
#include <cstring>
#include <type_traits>

namespace quadrix {
namespace {

constexpr char kScanMagic[8] = {'Q', 'D', 'X', 'M', 'S', 'C', 'A', 'N'};
constexpr char kEdgeMagic[8] = {'Q', 'D', 'X', 'M', 'E', 'D', 'G', 'E'};
constexpr std::uint32_t kTransferVersion = 1;

class Writer {
 public:
  explicit Writer(const char (&magic)[8]) {
    bytes_.append(magic, 8);
    put<std::uint32_t>(kTransferVersion);
  }
  template <typename T>
  void put(T value) {
    static_assert(std::is_trivially_copyable_v<T>);
    char raw[sizeof(T)];
    std::memcpy(raw, &value, sizeof(T));
    bytes_.append(raw, sizeof(T));
  }
  void put_text(const std::string& text) {
    put<std::uint64_t>(text.size());
    bytes_.append(text);
  }
  void put_matrix(const double* data, std::size_t count) {
    for (std::size_t k = 0; k < count; ++k) put<double>(data[k]);
  }
  std::string take() { return std::move(bytes_); }

 private:
  std::string bytes_;
};

class Reader {
 public:
  Reader(const std::string& bytes, const char (&magic)[8], const std::string& what, const std::string& source)
      : bytes_(bytes), what_(what), source_(source) {
    if (bytes_.size() < 12 || std::memcmp(bytes_.data(), magic, 8) != 0) fail("not a " + what_ + " (bad magic)");
    position_ = 8;
    const auto version = get<std::uint32_t>("version");
    if (version != kTransferVersion)
      fail("version " + std::to_string(version) + " (expected " + std::to_string(kTransferVersion) + ")");
  }
  template <typename T>
  T get(const char* field) {
    if (bytes_.size() - position_ < sizeof(T)) fail(std::string("truncated at ") + field);
    T value;
    std::memcpy(&value, bytes_.data() + position_, sizeof(T));
    position_ += sizeof(T);
    return value;
  }
  std::string get_text(const char* field) {
    const auto size = get<std::uint64_t>(field);
    if (bytes_.size() - position_ < size) fail(std::string("truncated in ") + field);
    std::string text = bytes_.substr(position_, size);
    position_ += size;
    return text;
  }
  void get_matrix(double* data, std::size_t count, const char* field) {
    for (std::size_t k = 0; k < count; ++k) data[k] = get<double>(field);
  }
  void finish() {
    if (position_ != bytes_.size()) fail(std::to_string(bytes_.size() - position_) + " bytes after the end");
  }
  [[noreturn]] void fail(const std::string& message) const { throw Error(source_ + ": " + what_ + ": " + message); }

 private:
  const std::string& bytes_;
  std::string what_, source_;
  std::size_t position_ = 0;
};

bool little_endian() {
  const std::uint16_t probe = 1;
  unsigned char first = 0;
  std::memcpy(&first, &probe, 1);
  return first == 1;
}

void require_little_endian() {
  if (!little_endian()) throw Error("map transfer bytes: this machine is big-endian; the format is little-endian only");
}

}  // namespace

std::string mapped_scan_to_bytes(const MappedScan& scan) {
  require_little_endian();
  Writer out(kScanMagic);
  out.put_text(scene_model_to_binary(scan.model));
  out.put<std::uint8_t>(scan.augmented ? 1 : 0);
  if (scan.augmented) out.put_text(scene_model_to_binary(*scan.augmented));
  out.put<std::uint64_t>(static_cast<std::uint64_t>(scan.descriptor.size()));
  out.put_matrix(scan.descriptor.data(), static_cast<std::size_t>(scan.descriptor.size()));
  out.put_text(scan.preset);
  out.put<double>(scan.modelling_ms);
  return out.take();
}

MappedScan mapped_scan_from_bytes(const std::string& bytes, const std::string& source_name) {
  require_little_endian();
  Reader in(bytes, kScanMagic, "mapped scan", source_name);
  MappedScan scan;
  scan.model = scene_model_from_binary(in.get_text("model"), source_name + " (model)");
  if (in.get<std::uint8_t>("augmented flag") != 0)
    scan.augmented = scene_model_from_binary(in.get_text("augmented model"), source_name + " (augmented model)");
  const auto size = in.get<std::uint64_t>("descriptor size");
  if (size > bytes.size() / sizeof(double)) in.fail("descriptor size " + std::to_string(size) + " beyond the bytes");
  scan.descriptor.resize(static_cast<Eigen::Index>(size));
  in.get_matrix(scan.descriptor.data(), static_cast<std::size_t>(size), "descriptor");
  scan.preset = in.get_text("preset");
  scan.modelling_ms = in.get<double>("modelling time");
  in.finish();
  return scan;
}

std::string map_edge_to_bytes(const MapEdge& edge) {
  require_little_endian();
  Writer out(kEdgeMagic);
  out.put<std::uint64_t>(edge.from);
  out.put<std::uint64_t>(edge.to);
  out.put<std::uint8_t>(edge.kind == MapEdgeKind::Loop ? 1 : 0);
  out.put_text(edge.status);
  out.put<std::uint8_t>(edge.used ? 1 : 0);
  out.put<std::uint8_t>(edge.across_sessions ? 1 : 0);
  const Eigen::Matrix4d transform = edge.transform.matrix();
  out.put_matrix(transform.data(), 16);
  out.put_matrix(edge.information.data(), 36);
  out.put<std::uint64_t>(edge.inliers);
  out.put<double>(edge.inlier_rmse);
  out.put_matrix(edge.registration_information.data(), 36);
  for (double value : {edge.overlap, edge.registration_ms, edge.chi2_before, edge.chi2_after, edge.dcs_scale}) out.put<double>(value);
  out.put_text(edge.note);
  return out.take();
}

MapEdge map_edge_from_bytes(const std::string& bytes, const std::string& source_name) {
  require_little_endian();
  Reader in(bytes, kEdgeMagic, "map edge", source_name);
  MapEdge edge;
  edge.from = static_cast<std::size_t>(in.get<std::uint64_t>("from"));
  edge.to = static_cast<std::size_t>(in.get<std::uint64_t>("to"));
  const auto kind = in.get<std::uint8_t>("kind");
  if (kind > 1) in.fail("kind " + std::to_string(kind) + " (expected 0 odometry or 1 loop)");
  edge.kind = kind == 1 ? MapEdgeKind::Loop : MapEdgeKind::Odometry;
  edge.status = in.get_text("status");
  edge.used = in.get<std::uint8_t>("used") != 0;
  edge.across_sessions = in.get<std::uint8_t>("across_sessions") != 0;
  Eigen::Matrix4d transform;
  in.get_matrix(transform.data(), 16, "transform");
  edge.transform.matrix() = transform;
  in.get_matrix(edge.information.data(), 36, "information");
  edge.inliers = static_cast<std::size_t>(in.get<std::uint64_t>("inliers"));
  edge.inlier_rmse = in.get<double>("inlier_rmse");
  in.get_matrix(edge.registration_information.data(), 36, "registration_information");
  for (double* value : {&edge.overlap, &edge.registration_ms, &edge.chi2_before, &edge.chi2_after, &edge.dcs_scale})
    *value = in.get<double>("numbers");
  edge.note = in.get_text("note");
  in.finish();
  return edge;
}

}  // namespace quadrix
