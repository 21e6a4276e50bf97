// Synthetic scenes with known ground truth: every scene is a list of bounded quadric
// primitives with semantic labels, so the scanner simulator (experiments/synthetic/scanner_simulator.h) can
// ray-cast them and every later stage (extraction, fitting, matching, registration) can be scored
// against the true primitives and the true sensor poses.
//
// World frame of every scene: metres, z up. A primitive's pose maps its canonical frame (the frame
// of Quadric::from_canonical: plane normal = axis a, cylinder/cone axis = axis c) into the world.
#pragma once

#include "geometry/mesh.h"
#include "geometry/quadric.h"
#include "geometry/quadric_record.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstdint>
#include <random>
#include <string>
#include <vector>

namespace quadrix {

/// Semantic labels of synthetic primitives. Where SemanticKITTI has a class for the same thing
/// its numeric id is reused (car 10, road 40, sidewalk 48, other-ground 49, building 50,
/// fence 51, vegetation 70, trunk 71, pole 80), so label-driven extraction written for
/// SemanticKITTI runs unchanged on synthetic clouds; classes it lacks take ids from 100 up.
enum class SemanticLabel : std::uint32_t {
  Unlabelled = 0,     ///< no primitive (never written for a hit)
  Car = 10,           ///< parked car body (ellipsoid)
  Person = 30,        ///< pedestrian (upright ellipsoid)
  Road = 40,          ///< drivable road surface (plane)
  Sidewalk = 48,      ///< raised pavement beside the road (plane)
  Ground = 49,        ///< other ground: plazas, verges (plane)
  Facade = 50,        ///< building facade, recess walls and jambs (plane)
  Barrier = 51,       ///< road barriers and noise walls (plane)
  Vegetation = 70,    ///< tree crown (ellipsoid)
  Trunk = 71,         ///< tree trunk (cylinder)
  Pole = 80,          ///< lamp posts, sign posts and their arms (thin cylinder, modelled as a line)
  Kerb = 100,         ///< vertical kerb face between road and sidewalk (plane)
  Bollard = 101,      ///< spherical stone bollard (sphere)
  TrafficCone = 102,  ///< traffic cone (cone)
  Column = 110,       ///< architectural column (cylinder)
  Wall = 111,         ///< wall of a monument, including the rotunda drum (plane or cylinder)
  Floor = 112,        ///< floor, podium top, step treads and ceilings (plane)
  Dome = 113,         ///< dome (clipped sphere)
  Roof = 114,         ///< roof slopes and conical roof rings (plane or cone)
  Step = 115,         ///< step risers and podium sides (plane)
  Pediment = 116,     ///< triangular pediment and entablature faces (plane)
  Ornament = 117,     ///< spherical finials and ornaments (sphere)
};

/// One row of the label table: numeric id, stable lower-case name and what it marks.
struct SemanticLabelInfo {
  SemanticLabel label = SemanticLabel::Unlabelled;  ///< the label
  std::string name;                                  ///< stable lower-case name ("road", "traffic_cone", ...)
  std::string description;                           ///< one line for people reading scene.json
};

/// Every label with its name and description, in ascending id order.
const std::vector<SemanticLabelInfo>& semantic_label_table();
/// Stable lower-case name of a label; throws quadrix::Error for an id not in the table.
std::string semantic_label_name(SemanticLabel label);
/// Parses a name of semantic_label_table(); throws quadrix::Error naming the text otherwise.
SemanticLabel semantic_label_from_name(const std::string& name);

/// One bounded ground-truth surface of a scene.
struct ScenePrimitive {
  std::uint32_t id = 0;                                    ///< index in Scene::primitives (written as "primitive_id")
  std::string name;                                        ///< readable unique name, e.g. "facade_left_03_recess_back"
  SemanticLabel label = SemanticLabel::Unlabelled;         ///< semantic class
  QuadricType surface_type = QuadricType::Plane;           ///< simulated surface: plane, sphere, ellipsoid, circular/elliptic cylinder, circular/elliptic cone
  QuadricType model_type = QuadricType::Plane;             ///< type a modelling run should fit (poles: line; otherwise surface_type)
  Eigen::Vector3d scale = Eigen::Vector3d::Ones();         ///< canonical scales (radii in metres; cones: tan of half-angles and 1)
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();  ///< canonical frame -> world
  LocalExtent extent;                                      ///< bounds of the surface in the canonical frame
  std::vector<Eigen::Vector2d> polygon;                    ///< planes only: optional convex polygon (b, c), counter-clockwise, further bounding the rectangle
  /// > 0: a porous volume (foliage) bounded by the closed surface: a ray that enters it stops after
  /// an exponentially distributed depth with this mean, metres, or passes through when that depth
  /// exceeds its chord. 0: a solid surface (the ray stops where it meets it).
  double mean_free_path = 0.0;
};

/// A scene: its primitives plus the default sensor placements a user gets without --poses.
struct Scene {
  std::string name;                                     ///< "street", "corridor" or "monument"
  std::uint64_t seed = 0;                               ///< seed the layout was drawn with
  std::vector<ScenePrimitive> primitives;               ///< ids equal indices
  std::vector<Eigen::Isometry3d> default_lidar_poses;   ///< a registration pair for vehicle LiDARs (sensor -> world)
  std::vector<Eigen::Isometry3d> default_tls_stations;  ///< six terrestrial scanner stations (sensor -> world)
  std::string description;                              ///< one paragraph for scene.json
};

/// Names accepted by make_scene, in listing order.
std::vector<std::string> scene_names();
/// One-line description of a scene name; throws quadrix::Error for unknown names.
std::string scene_description(const std::string& name);
/// How the street scene's vegetation is simulated.
enum class Foliage {
  Solid,   ///< tree crowns are closed ellipsoid surfaces (the default)
  Porous,  ///< crowns are porous volumes, and hedges line the facades (ScenePrimitive::mean_free_path)
};
/// Parses "solid" or "porous"; throws quadrix::Error naming `context` otherwise.
Foliage foliage_from_name(const std::string& name, const std::string& context);
/// Options of the street scene beyond its seed.
struct StreetOptions {
  Foliage foliage = Foliage::Solid;  ///< solid crowns, or porous crowns plus hedges
  /// A level road (gradient 0) so streets join at intersections of one height (the town drive);
  /// the gradient is still drawn, so the rest of the layout equals the sloped street's.
  bool level = false;
};
/// Builds a scene by name ("street", "corridor", "monument"); `street` applies to the street only.
/// Throws quadrix::Error for unknown names and for porous foliage asked of another scene.
Scene make_scene(const std::string& name, std::uint64_t seed, const StreetOptions& street = {});
/// KITTI-like urban block with a random layout per seed (sloped road, recessed facades, poles,
/// trees, parked cars, kerbs, bollards, traffic cones), closed by cross facades at both ends. With
/// porous foliage the crowns let rays in (mean free path 0.4 m) and porous hedges 0.8-2 m tall
/// and 2-9 m long line most of the facades; everything else is drawn as with solid foliage.
Scene make_street_scene(std::uint64_t seed, const StreetOptions& options = {});
/// One drive along a street scene: the scene as that drive saw it and the sensor poses of its scans.
struct StreetPass {
  Scene scene;                                ///< the street with this pass's parked cars and pedestrians
  std::vector<Eigen::Isometry3d> poses;       ///< sensor -> world, one per scan, in driving order
};
/// A drive along make_street_scene(seed, options): the same road, buildings, poles and trees, with the parked
/// cars re-drawn (each kept with probability 0.5, new ones in free kerb space) and 6-14 pedestrians,
/// all drawn from (seed, pass). Odd passes drive +x in the right lane, even passes -x in the left lane
/// (the opposite direction); one scan every `scan_spacing` metres for x in [-48, 48] (passes after the
/// first offset by half a spacing), each with +-0.5 m of lateral and +-4 degrees of heading jitter. Throws
/// quadrix::Error when pass < 1 or scan_spacing is not positive.
StreetPass make_street_pass(std::uint64_t seed, int pass, double scan_spacing, const StreetOptions& options = {});
/// Long straight road between continuous barriers and noise walls with evenly spaced poles and no
/// end walls: translation along the road is unobservable (degenerate registration).
Scene make_corridor_scene(std::uint64_t seed);
/// Pantheon-like monument: exactly 33 cylinders, 25 planes, 3 spheres and 1 cone (counted by
/// model_type), the paper's modelling result. The seed only varies the default sensor poses' yaw.
Scene make_monument_scene(std::uint64_t seed);

/// The simulated surface as a quadric: Quadric::from_canonical(surface_type, scale, pose).
Quadric surface_quadric(const ScenePrimitive& primitive);
/// The quadric a modelling run should recover: Quadric::from_canonical(model_type, scale, pose).
Quadric model_quadric(const ScenePrimitive& primitive);
/// The primitive's surface in decomposed form (type, scale, rotation, centre = the primitive's own
/// canonical frame, so `extent` applies to it), for orthogonal_distance, sample_surface, mesh_surface.
QuadricDecomposition primitive_shape(const ScenePrimitive& primitive);
/// True when a point given in the primitive's canonical frame lies inside its extent and polygon,
/// allowing `tolerance` metres.
bool inside_primitive_bounds(const ScenePrimitive& primitive, const Eigen::Vector3d& local_point, double tolerance = 0.0);
/// Points spread over the bounded true surface about `spacing` metres apart, in the world frame.
/// Deterministic; used for the ground-truth statistics and for pictures.
Eigen::Matrix3Xd sample_primitive_surface(const ScenePrimitive& primitive, double spacing);
/// Approximate area of the bounded surface in square metres (from the same parametrisation).
double primitive_surface_area(const ScenePrimitive& primitive);
/// The 21-number ground-truth record (paper Struct. 1): model quadric completed with the
/// statistical pose of about `sample_count` true surface samples.
QuadricRecord ground_truth_record(const ScenePrimitive& primitive, int sample_count = 4000);

/// Number of primitives per model type name ("plane", "circular_cylinder", ...).
std::vector<std::pair<std::string, int>> count_model_types(const Scene& scene);

/// Deterministic random numbers identical on every standard library: std::mt19937_64 is fully
/// specified by the standard, the distributions below are implemented here (the std:: ones are not).
class PortableRandom {
 public:
  /// Seeds the 64-bit Mersenne Twister.
  explicit PortableRandom(std::uint64_t seed) : engine_(seed) {}
  /// Uniform double in [minimum, maximum) from the top 53 bits of one draw.
  double uniform(double minimum, double maximum);
  /// Uniform integer in [minimum, maximum] (inclusive); requires minimum <= maximum.
  int uniform_integer(int minimum, int maximum);
  /// True with the given probability.
  bool bernoulli(double probability);
  /// Normal deviate (Box-Muller, one of each pair).
  double normal(double mean, double standard_deviation);

 private:
  std::mt19937_64 engine_;
};

/// SplitMix64 hash of a 64-bit value: the counter-based randomness used per ray, so results do not
/// depend on how rays are split between threads.
std::uint64_t mix_bits(std::uint64_t value);
/// Uniform double in [0, 1) from a hash value (top 53 bits).
double unit_interval_from_bits(std::uint64_t bits);

}  // namespace quadrix
