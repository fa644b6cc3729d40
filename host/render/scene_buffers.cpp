// Scene upload and the uniform-or-storage choice (see scene_buffers.h).
#include "render/scene_buffers.h"

#include <algorithm>
#include <chrono>
#include <string>

#include "accel/bvh_records.h"
#include "util/error.h"

namespace vkray {

namespace {

using Clock = std::chrono::steady_clock;

template <typename T>
void uploadArray(std::unique_ptr<vulkan::Buffer>& buffer, const vulkan::Context& ctx, const std::vector<T>& data,
                 const std::string& name) {
  buffer = std::make_unique<vulkan::Buffer>(ctx, data.size() * sizeof(T), vk::BufferUsageFlagBits::eStorageBuffer,
                                            vulkan::MemoryUse::DeviceLocal, name);
  buffer->write(data.data(), data.size() * sizeof(T));
}

template <typename T>
void uploadTexels(std::unique_ptr<vulkan::Buffer>& buffer, const vulkan::Context& ctx, const std::vector<T>& data,
                  vk::Format format, const std::string& name) {
  buffer.reset(); // the old array's memory goes back first
  buffer = std::make_unique<vulkan::Buffer>(ctx, data.size() * sizeof(T), format, vulkan::MemoryUse::DeviceLocal, name);
  buffer->write(data.data(), data.size() * sizeof(T));
}

// Copies an array into its slot of the packed SceneUbo.
template <typename T, std::size_t N> void packUniform(T (&slot)[N], const std::vector<T>& data) {
  std::copy(data.begin(), data.end(), slot);
}

} // namespace

SceneBuffers::SceneBuffers(const vulkan::Context& context) : context_(context) {
  buffers_.resize(gpu::kBindingCount);
}

void SceneBuffers::upload(const GpuScene& g) {
  auto start = Clock::now();
  uploadArray(buffers_[gpu::kBindingMaterials], context_, g.materials, "materials");
  uploadArray(buffers_[gpu::kBindingLights], context_, g.lights, "lights");
  uploadArray(buffers_[gpu::kBindingSpheres], context_, g.spheres, "spheres");
  uploadArray(buffers_[gpu::kBindingPlanes], context_, g.planes, "planes");
  uploadTexels(buffers_[gpu::kBindingTriangles], context_, g.triangles, vk::Format::eR32G32B32A32Uint, "triangles");
  uploadArray(buffers_[gpu::kBindingPolygons], context_, g.polygons, "polygons");
  uploadArray(buffers_[gpu::kBindingPolyVertices], context_, g.polyVertices, "polygon vertices");
  uploadTexels(buffers_[gpu::kBindingNormals], context_, g.normals, vk::Format::eR32G32B32A32Sfloat, "shading normals");
  uploadTexels(buffers_[gpu::kBindingTexCoords], context_, g.texCoords, vk::Format::eR32G32B32A32Sfloat,
               "texture coordinates");
  uploadTexels(buffers_[gpu::kBindingTextureInfo], context_, g.textureInfo, vk::Format::eR32G32B32A32Uint,
               "texture records");
  uploadTexels(buffers_[gpu::kBindingTexels], context_, g.texels, vk::Format::eR32G32B32A32Sfloat, "textures");
  uploadBvhNodes(g);
  uploadTexels(buffers_[gpu::kBindingPrimRefs], context_, g.bvh.primRefs, vk::Format::eR32Uint,
               "BVH primitive references");
  shadingFitsUbo_ = g.materials.size() <= gpu::kUboMaterials && g.lights.size() <= gpu::kUboLights &&
                    g.planes.size() <= gpu::kUboPlanes;
  sceneFitsUbo_ = shadingFitsUbo_ && g.spheres.size() <= gpu::kUboSpheres && g.triangles.size() <= gpu::kUboTriangles &&
                  g.polygons.size() <= gpu::kUboPolygons && g.polyVertices.size() <= gpu::kUboPolyVertices;
  // The uniform copy always exists at full size (the shader declares fixed arrays); the materials,
  // lights and planes are filled in when they fit, the primitives when the whole scene does.
  auto packed = std::make_unique<gpu::SceneUbo>();
  if (shadingFitsUbo_) {
    packUniform(packed->materials, g.materials);
    packUniform(packed->lights, g.lights);
    packUniform(packed->planes, g.planes);
  }
  if (sceneFitsUbo_) {
    packUniform(packed->spheres, g.spheres);
    packUniform(packed->triangles, g.triangles);
    packUniform(packed->polygons, g.polygons);
    packUniform(packed->polyVertices, g.polyVertices);
  }
  buffers_[gpu::kBindingSceneUbo] =
      std::make_unique<vulkan::Buffer>(context_, sizeof(gpu::SceneUbo), vk::BufferUsageFlagBits::eUniformBuffer,
                                       vulkan::MemoryUse::DeviceLocal, "small scene (uniform)");
  buffers_[gpu::kBindingSceneUbo]->write(packed.get(), sizeof(gpu::SceneUbo));
  uploadMs_ = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

void SceneBuffers::uploadBvhNodes(const GpuScene& g) {
  // The records, then the shadow entry points' table (FrameParams::shadowEntryBase).
  auto& nodes = buffers_[gpu::kBindingBvhNodes];
  const std::vector<glm::uvec4> records = packBvhRecords(g.bvhNodes);
  const std::size_t recordBytes = records.size() * sizeof(glm::uvec4);
  const std::size_t tableBytes = g.shadowEntries.size() * sizeof(glm::uvec4);
  nodes.reset(); // the old array's memory goes back first
  nodes = std::make_unique<vulkan::Buffer>(context_, recordBytes + tableBytes, vk::Format::eR32G32B32A32Uint,
                                           vulkan::MemoryUse::DeviceLocal, "BVH nodes");
  nodes->write(records.data(), recordBytes);
  if (tableBytes > 0) nodes->write(g.shadowEntries.data(), tableBytes, recordBytes);
}

SceneMemoryUse SceneBuffers::memoryFor(SceneMemory requested) const {
  const bool cpu = context_.info().type == "CPU";
  SceneMemoryUse use;
  switch (requested) {
  case SceneMemory::Uniform:
    if (!sceneFitsUbo_) throw InputError("--scene-memory", "the scene's arrays exceed the uniform-buffer capacities");
    use.scene = true;
    break;
  case SceneMemory::Storage:
    break;
  case SceneMemory::Auto:
    use.scene = sceneFitsUbo_ && cpu;
    use.shading = use.scene || (shadingFitsUbo_ && cpu);
    return use;
  }
  use.shading = use.scene;
  return use;
}

HostPageUse SceneBuffers::hostPages() const {
  HostPageUse use;
  for (const auto& buffer : buffers_) {
    if (const vulkan::HostPages* pages = buffer ? buffer->hostPages() : nullptr) {
      use.bytes += pages->size();
      use.hugeBytes += pages->hugeBytes();
    }
  }
  return use;
}

} // namespace vkray
