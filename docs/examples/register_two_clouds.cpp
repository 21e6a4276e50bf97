// Registers SOURCE onto TARGET and prints the 4x4 transform (source -> target frame) and the status.
#include "estimation/registration.h"
#include "geometry/io.h"

#include <iostream>

int main(int argc, char** argv) {
  if (argc != 3) {
    std::cerr << "usage: " << argv[0] << " SOURCE TARGET\n";
    return 2;
  }
  const quadrix::PointCloud source = quadrix::read_point_cloud(argv[1]);
  const quadrix::PointCloud target = quadrix::read_point_cloud(argv[2]);
  const quadrix::RegistrationResult result = quadrix::register_clouds(source, target);
  std::cout << result.transform.matrix() << "\n"
            << quadrix::registration_status_name(result.status) << ": " << result.message << "\n";
  return result.status == quadrix::RegistrationStatus::Ok ? 0 : 1;
}
