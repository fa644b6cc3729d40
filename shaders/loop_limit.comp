// The driver's loop cut, measured (host/vk/loop_limit.cpp): one invocation runs a loop of pc.turns
// turns and writes how many it ran. Mesa 22's llvmpipe ends every loop of an invocation once its
// SIMD group has run 65535 iterations in all; Mesa 25's and GPUs' drivers run a loop to its end.
// The body is a linear congruential step whose state is written too, so that no compiler can
// replace the loop by its closed form.
#version 460

layout(local_size_x = 1, local_size_y = 1, local_size_z = 1) in;

layout(std430, binding = 0) writeonly buffer Result {
  uint turns;
  uint state;
} result;
layout(push_constant) uniform Push { uint turns; } pc;

void main() {
  uint i = 0u;
  uint x = 1u;
  while (i < pc.turns) {
    x = x * 1664525u + 1013904223u;
    ++i;
  }
  result.turns = i;
  result.state = x;
}
