// Seeded, platform-independent random numbers: the standard library's distributions are
// implementation-defined, and MODEL.md requires identical trajectories for identical seeds.
// xoshiro256** seeded through splitmix64; normals by Box-Muller from 53-bit uniforms.
#pragma once

#include <cmath>
#include <cstdint>
#include <numbers>

namespace leakmon::sim {

// One 64-bit step of splitmix64: derives independent stream seeds from one scenario seed.
constexpr std::uint64_t splitmix64(std::uint64_t& state) {
  std::uint64_t z = (state += 0x9e3779b97f4a7c15ULL);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

// Seed of the named stream `stream` of a scenario seed (reference, flow noise, sensors...).
constexpr std::uint64_t stream_seed(std::uint64_t seed, std::uint64_t stream) {
  std::uint64_t s = seed ^ (stream * 0xd1b54a32d192ed03ULL);
  splitmix64(s);
  return splitmix64(s);
}

class Random {
 public:
  explicit Random(std::uint64_t seed = 0) { reseed(seed); }

  void reseed(std::uint64_t seed) {
    std::uint64_t s = seed;
    for (auto& word : state_) word = splitmix64(s);
    spare_valid_ = false;
  }

  std::uint64_t next() noexcept {
    const std::uint64_t result = rotl(state_[1] * 5, 7) * 9;
    const std::uint64_t t = state_[1] << 17;
    state_[2] ^= state_[0];
    state_[3] ^= state_[1];
    state_[1] ^= state_[2];
    state_[0] ^= state_[3];
    state_[2] ^= t;
    state_[3] = rotl(state_[3], 45);
    return result;
  }

  // Uniform in [0, 1).
  double uniform() noexcept { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
  double uniform(double lo, double hi) noexcept { return lo + (hi - lo) * uniform(); }

  // Standard normal (Box-Muller, both values used).
  double normal() noexcept {
    if (spare_valid_) {
      spare_valid_ = false;
      return spare_;
    }
    const double u1 = 1.0 - uniform();  // (0, 1]: log() stays finite
    const double u2 = uniform();
    const double radius = std::sqrt(-2.0 * std::log(u1));
    const double angle = 2.0 * std::numbers::pi * u2;
    spare_ = radius * std::sin(angle);
    spare_valid_ = true;
    return radius * std::cos(angle);
  }

 private:
  static constexpr std::uint64_t rotl(std::uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }

  std::uint64_t state_[4] = {};
  double spare_ = 0.0;
  bool spare_valid_ = false;
};

// Stream numbers, so that switching one source of randomness off leaves the others unchanged.
enum class RandomStream : std::uint64_t {
  reference = 1,
  flow_noise = 2,
  sensors = 3,
  sensor_faults = 4
};

constexpr std::uint64_t stream_seed(std::uint64_t seed, RandomStream stream) {
  return stream_seed(seed, static_cast<std::uint64_t>(stream));
}

}  // namespace leakmon::sim
