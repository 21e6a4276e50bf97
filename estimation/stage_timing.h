// Wall time of the registration's stages, recorded in RegistrationResult::timings_ms by the
// conductor and by every stage it calls. Internal to estimation/.
#pragma once

#include "estimation/registration_types.h"

#include <chrono>
#include <type_traits>

namespace quadrix::stage_timing {

/// The clock of every stage timing.
using Clock = std::chrono::steady_clock;

/// Milliseconds since `start`.
inline double elapsed_ms(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

/// Runs `stage` and adds its wall time to `result.timings_ms[name]`; returns what it returns.
template <typename Stage>
auto timed(RegistrationResult& result, const char* name, Stage&& stage) {
  const Clock::time_point start = Clock::now();
  if constexpr (std::is_void_v<decltype(stage())>) {
    stage();
    result.timings_ms[name] += elapsed_ms(start);
  } else {
    auto value = stage();
    result.timings_ms[name] += elapsed_ms(start);
    return value;
  }
}

}  // namespace quadrix::stage_timing
