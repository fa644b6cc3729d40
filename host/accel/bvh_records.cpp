// Packing the BVH records into three texels (see bvh_records.h).
#include "accel/bvh_records.h"

#include <algorithm>
#include <bit>
#include <cmath>

#include "util/error.h"

namespace vkray {

namespace {

constexpr std::uint32_t kSign = 0x80000000u;
constexpr std::uint32_t kByte = 0xFFu;
constexpr std::uint32_t kBlock = 0x100u; // one step of the bits above the low byte

// Magnitudes are compared as integers: for finite floats of one sign, a larger magnitude's bits are
// a larger integer. Each bound moves one whole block of 256 ulps (2^-15 of its value, or the smallest
// normal's neighbourhood near zero) outwards, so any low byte leaves it outside the exact value.
// A bound moved towards zero may be a denormal, which a device may flush to zero: further towards zero,
// still outside the exact value. One moved away from zero is at least the smallest normal, so that no
// flush can bring it back inside.
std::uint32_t awayFromZero(std::uint32_t bits) { // same sign, magnitude rounded up to a whole block
  constexpr std::uint32_t kSmallestNormal = 0x00800000u;
  std::uint32_t sign = bits & kSign;
  std::uint32_t magnitude = ((bits & ~kSign) + kByte) & ~kByte;
  return sign | std::max(magnitude, kSmallestNormal);
}

std::uint32_t towardsZero(std::uint32_t bits, bool crossToNegative) { // magnitude a block below, or across zero
  std::uint32_t magnitude = (bits & ~kSign) & ~kByte;
  if (magnitude >= kBlock) return (bits & kSign) | (magnitude - kBlock);
  return crossToNegative ? kSign | kBlock : kBlock; // past zero: a tiny value of the other sign
}

void checkRange(float v) {
  if (!(std::fabs(v) <= 1e38f)) throw Error("BVH record: box coordinate " + std::to_string(v) + " beyond ±1e38");
}

// `v` moved outwards (upwards for an upper bound, downwards for a lower one) with `byte` in its low
// bits: away from zero where outwards is away from zero (v nonzero, of that sign), else towards it.
std::uint32_t boundWithByte(float v, std::uint32_t byte, bool upper) {
  checkRange(v);
  std::uint32_t bits = std::bit_cast<std::uint32_t>(v);
  bool nonzero = (bits & ~kSign) != 0u;
  bool negative = (bits & kSign) != 0u;
  bool away = nonzero && negative != upper;
  std::uint32_t bound = away ? awayFromZero(bits) : towardsZero(bits, !upper);
  return (bound & ~kByte) | (byte & kByte);
}

} // namespace

std::uint32_t lowerBoundWithByte(float v, std::uint32_t byte) {
  return boundWithByte(v, byte, false);
}

std::uint32_t upperBoundWithByte(float v, std::uint32_t byte) {
  return boundWithByte(v, byte, true);
}

std::vector<glm::uvec4> packBvhRecords(const std::vector<gpu::BvhWideNode>& nodes) {
  auto byteOf = [](std::uint32_t ref, int k) { return (ref >> (8 * k)) & kByte; };
  auto exact = [](float v) {
    checkRange(v);
    return std::bit_cast<std::uint32_t>(v);
  };
  std::vector<glm::uvec4> texels(nodes.size() * gpu::kBvhRecordTexels);
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    const gpu::BvhWideNode& n = nodes[i];
    glm::uvec4* t = &texels[i * gpu::kBvhRecordTexels];
    // ref0 in the low bytes of min0.xyz and max0.x, ref1 in those of max0.yz and min1.xy.
    t[0] = glm::uvec4(lowerBoundWithByte(n.min0.x, byteOf(n.ref0, 0)), lowerBoundWithByte(n.min0.y, byteOf(n.ref0, 1)),
                      lowerBoundWithByte(n.min0.z, byteOf(n.ref0, 2)), upperBoundWithByte(n.max0.x, byteOf(n.ref0, 3)));
    t[1] = glm::uvec4(upperBoundWithByte(n.max0.y, byteOf(n.ref1, 0)), upperBoundWithByte(n.max0.z, byteOf(n.ref1, 1)),
                      lowerBoundWithByte(n.min1.x, byteOf(n.ref1, 2)), lowerBoundWithByte(n.min1.y, byteOf(n.ref1, 3)));
    t[2] = glm::uvec4(exact(n.min1.z), exact(n.max1.x), exact(n.max1.y), exact(n.max1.z));
  }
  return texels;
}

gpu::BvhWideNode unpackBvhRecord(const std::vector<glm::uvec4>& texels, std::uint32_t record) {
  const glm::uvec4* t = &texels[std::size_t(record) * gpu::kBvhRecordTexels];
  auto ref = [](glm::uvec4 v) { return (v.x & kByte) | (v.y & kByte) << 8 | (v.z & kByte) << 16 | v.w << 24; };
  auto f = [](std::uint32_t b) { return std::bit_cast<float>(b); };
  gpu::BvhWideNode n{};
  n.min0 = glm::vec3(f(t[0].x), f(t[0].y), f(t[0].z));
  n.ref0 = ref(t[0]);
  n.max0 = glm::vec3(f(t[0].w), f(t[1].x), f(t[1].y));
  n.ref1 = ref(t[1]);
  n.min1 = glm::vec3(f(t[1].z), f(t[1].w), f(t[2].x));
  n.max1 = glm::vec3(f(t[2].y), f(t[2].z), f(t[2].w));
  return n;
}

} // namespace vkray
