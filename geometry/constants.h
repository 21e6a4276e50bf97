// Numeric constants shared by the library, the experiments and the tests.
#pragma once

namespace quadrix {

/// pi to double precision (the same value as the POSIX M_PI, which standard C++17 does not define).
inline constexpr double kPi = 3.14159265358979323846;

}  // namespace quadrix
