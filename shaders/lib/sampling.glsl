// Sub-pixel sample positions: the pixel centre for single-sample renders, otherwise an Owen-scrambled
// Sobol (0,2)-sequence per pixel. Any power-of-two prefix of it is stratified in every elementary
// interval (4 samples: one per quadrant; 16: one per 4x4 cell and per 1x16 strip), and a progressive
// viewer that draws sample k in frame k sees exactly the samples a headless --spp N render uses.
#ifndef VKRAY_SAMPLING_GLSL
#define VKRAY_SAMPLING_GLSL

#include "common.glsl"

// First two Sobol dimensions as 0.32 fixed point, without a loop over the index's bits (on a CPU
// driver such a loop runs 32 times for a scrambled index, in every lane). Dimension 0 is the van der
// Corput sequence: the index's bits reversed. Dimension 1 has direction numbers
// v_k = v_(k-1) ^ (v_(k-1) >> 1) from v_0 = 2^31, i.e. bit 31 - j of v_k is C(k, j) mod 2, which by
// Lucas' theorem is 1 exactly when j's bits are a subset of k's. So bit 31 - j of the result is the
// XOR of the index's bits k over the supersets k of j: a superset-sum transform over the 5 bit
// positions of j, one shift-and-mask step each, then the bits reversed. (Equal to the direction-
// number loop for every index: tests/antialiasing_test.cpp, SobolClosedFormEqualsDirectionNumbers.)
uvec2 sobol2(uint index) {
  uint w = index;
  w ^= (w >> 1u) & 0x55555555u;
  w ^= (w >> 2u) & 0x33333333u;
  w ^= (w >> 4u) & 0x0F0F0F0Fu;
  w ^= (w >> 8u) & 0x00FF00FFu;
  w ^= (w >> 16u) & 0x0000FFFFu;
  return uvec2(bitfieldReverse(index), bitfieldReverse(w));
}

// Nested uniform (Owen) scrambling of a 32-bit fixed-point value, applied to its bit-reversed form so
// that the hash mixes only higher bits into lower ones (Burley, "Practical Hash-based Owen
// Scrambling", JCGT 9(4), 2020, after Laine & Karras 2011).
uint laineKarrasPermutation(uint x, uint seed) {
  x += seed;
  x ^= x * 0x6c50b47cu;
  x ^= x * 0xb82f1e52u;
  x ^= x * 0xc7afe638u;
  x ^= x * 0x8d22f6e6u;
  return x;
}

uint nestedUniformScramble(uint x, uint seed) {
  x = bitfieldReverse(x);
  x = laineKarrasPermutation(x, seed);
  return bitfieldReverse(x);
}

// Sample `index` of pixel `pixelSeed`, in [0, 1)^2. The index itself is Owen-scrambled first, which
// shuffles the order of the sequence per pixel without breaking its power-of-two stratification.
vec2 sobolOwenSample(uint index, uint pixelSeed) {
  uint shuffled = nestedUniformScramble(index, hashPcg(pixelSeed));
  uvec2 s = sobol2(shuffled);
  uint x = nestedUniformScramble(s.x, hashPcg(pixelSeed ^ 0x5bd1e995u));
  uint y = nestedUniformScramble(s.y, hashPcg(pixelSeed ^ 0x1b873593u));
  return vec2(float(x >> 8u), float(y >> 8u)) * (1.0 / 16777216.0);
}

// The thin lens's point for sample `index` of pixel `pixelSeed`, in [0, 1)^2: the same (0,2)-sequence
// with other scrambling seeds. The index is shuffled by its own scramble, so a sample's lens point is
// decorrelated from its sub-pixel offset, and each is stratified on its own (Burley 2020, sec. 4:
// padding dimension pairs by independent shuffles).
vec2 lensSample(uint index, uint pixelSeed) { return sobolOwenSample(index, hashPcg(pixelSeed ^ 0x68e31da4u)); }

#endif
