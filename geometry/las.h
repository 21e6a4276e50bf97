// The public header block of an ASPRS LAS 1.0-1.4 file, for `quadrix info` and streaming readers.
// Point data is read with read_point_cloud (geometry/io.h) or open_point_stream (geometry/point_stream.h).
#pragma once

#include "geometry/io.h"

#include <Eigen/Core>

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>

namespace quadrix {

/// The length units a LAS file's coordinate reference system declares, from its GeoTIFF keys
/// (LASF_Projection 34735/34736: ProjLinearUnitsGeoKey 3076, ProjLinearUnitSizeGeoKey 3077,
/// VerticalUnitsGeoKey 4099, GTModelTypeGeoKey 1024) or its OGC WKT (LASF_Projection 2112: the UNIT
/// of PROJCS and of VERT_CS). Malformed CRS records leave the units undeclared: they never stop
/// the points from being read.
struct LasUnits {
  double horizontal_metres = 0.0;        ///< metres per x/y unit (0: not declared, or angular)
  double vertical_metres = 0.0;          ///< metres per z unit (0: not declared; then the horizontal unit is the usual reading)
  std::string horizontal_name;           ///< e.g. "metre", "foot", "US survey foot", "degree" (geographic); empty: not declared
  std::string vertical_name;             ///< the z unit's name, empty when not declared
  std::string source;                    ///< "GeoTIFF keys", "WKT", or empty
  bool geographic = false;               ///< x/y are longitude/latitude in degrees (GTModelType 2 or a WKT without PROJCS)
};

/// What a LAS public header declares, checked against the file (see read_las_header).
struct LasHeader {
  int version_major = 1;                 ///< 1
  int version_minor = 2;                 ///< 0..4
  int point_format = 0;                  ///< point data record format 0..10
  std::size_t header_size = 0;           ///< bytes of the public header block
  std::size_t point_data_offset = 0;     ///< byte where the point records start
  std::size_t record_length = 0;         ///< bytes a point record (base size of the format + extra bytes)
  std::size_t extra_bytes = 0;           ///< record_length minus the format's base size
  std::uint64_t point_count = 0;         ///< records (LAS 1.4: the 64-bit count when set)
  std::size_t vlr_count = 0;             ///< variable-length records before the points
  Eigen::Vector3d scale = Eigen::Vector3d::Ones();   ///< x = X * scale + offset (double)
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();  ///< see scale
  Eigen::Vector3d min = Eigen::Vector3d::Zero();     ///< header bounding box, file coordinates
  Eigen::Vector3d max = Eigen::Vector3d::Zero();     ///< header bounding box, file coordinates
  std::string system_identifier;         ///< as written (trailing NULs removed)
  std::string generating_software;       ///< as written (trailing NULs removed)
  std::size_t file_size = 0;             ///< bytes of the whole file
  LasUnits units;                        ///< coordinate units the file's CRS records declare
};

/// Base record size of each LAS point data record format 0..10 (LAS 1.4 R15, section 2.6).
inline constexpr std::array<std::size_t, 11> kLasBaseRecordSize = {20, 28, 26, 34, 57, 63, 30, 36, 38, 59, 67};

/// Reads and checks a LAS public header: signature, version, header size, point format and record
/// length, point count (legacy and 64-bit) and offset against the file size, variable-length
/// records inside the header area, finite non-zero scales and finite offsets and bounds. Throws
/// quadrix::Error naming the file and the field; a LAZ file (compressed point format or LASzip
/// record) gets an error naming laszip and pdal translate, which decompress it.
LasHeader read_las_header(const std::string& path);

/// The length unit of a point-cloud file's coordinates, as modelling needs it: every preset's
/// lengths are metres, so a cloud in another unit is modelled scaled to metres and its model is
/// written back in the file's unit.
struct CoordinateUnits {
  double metres_per_unit = 1.0;  ///< 1: metres, declared or assumed
  std::string name = "metre";    ///< as the file declares it ("foot", "US survey foot", ...)
  std::string source;            ///< "LAS GeoTIFF keys", "LAS WKT", or empty (nothing declared: metres assumed)
  bool las = false;              ///< the file is LAS, so its labels are ASPRS classes
};

/// The unit of `path`'s coordinates: what a LAS file's CRS records declare (LasHeader::units: feet in
/// most US state-plane surveys); metres for every other format (`format` Auto: by extension) and
/// for a LAS file that declares none. Throws quadrix::Error naming the file for a geographic CRS
/// (degrees are not lengths) and for z declared in another unit than x and y.
CoordinateUnits coordinate_units(const std::string& path, CloudFormat format = CloudFormat::Auto);

/// Throws quadrix::Error naming `path` when `units` are not metres: for the stages that work in
/// metres only (`what`: "registration", "a map"), so a scan in feet is never taken for metres.
void require_metres(const CoordinateUnits& units, const std::string& path, const std::string& what);

}  // namespace quadrix
