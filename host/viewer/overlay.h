// The viewer's overlay (Dear ImGui): timings, ray statistics and the scene's Features, and controls for
// the accuracy knobs and effects. On the direct path (presenter.h) the panel is drawn on a
// transparent layer only when it changes, and the resolve pass composites that layer; on the blit
// path it is drawn on the blitted swapchain image every frame.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <vulkan/vulkan_raii.hpp>

#include "render/renderer.h"
#include "viewer/camera_controller.h"
#include "viewer/convergence.h"
#include "viewer/device_image.h"
#include "viewer/swapchain.h"
#include "viewer/view_settings.h"
#include "viewer/window.h"
#include "vk/context.h"

namespace vkray {

// What the overlay shows; the frame loop fills it.
struct OverlayModel {
  std::string scenePath;
  std::string device;
  std::string presentMode;
  vk::Extent2D renderSize{0, 0};
  std::uint32_t samples = 0; // accumulated per pixel
  double frameMs = 0.0;      // wall time between frames
  double hostMs = 0.0;       // CPU time of the frame loop outside waits for the GPU
  double traceMs = 0.0;      // GPU times, per frame
  double resolveMs = 0.0;
  double blitMs = 0.0;
  double overlayMs = 0.0;
  double raysPerSecond = 0.0;
  RayStats raysPerFrame; // averaged over the last statistics interval
  std::vector<std::string> features;
  std::string cameraJson;
  CameraMode cameraMode = CameraMode::Orbit;
  std::string reloadError; // the scene file's last load error (the last good scene is shown)
  std::string status;      // the last action's result ("saved shot.png")
  DisplayMode display = DisplayMode::Image;
  double noiseThreshold = 0.0;   // convergence is judged at this threshold
  bool defaultThreshold = false; // neither the scene nor --noise-threshold set it
  ConvergenceFigures convergence;
  // The inspected pixel's ray tree (a click), drawn over the image and listed; null: none. camera:
  // the frame the rays are projected with, for an image of renderSize.
  const RayTree* rayTree = nullptr;
  CameraFrame camera{};
};

// What the user asked for through the overlay's buttons this frame.
struct OverlayRequests {
  bool resetCamera = false;
  bool saveCamera = false;
  bool screenshot = false;
  bool toggleFly = false;
  bool closeRayTree = false;
};

class Overlay {
public:
  Overlay(const vulkan::Context& context, const Window& window, const Swapchain& swapchain);
  ~Overlay();
  Overlay(const Overlay&) = delete;
  Overlay& operator=(const Overlay&) = delete;

  // Framebuffers for the swapchain's current images and a layer of their size (after every
  // re-creation); detach() drops the framebuffers before the swapchain's image views go.
  void attach(const Swapchain& swapchain);
  void detach() { framebuffers_.clear(); }

  // Starts the overlay's frame; then the input it claims is known.
  void newFrame();
  bool wantsMouse() const;
  bool wantsKeyboard() const;
  // Builds the panel (when visible); edits `settings` in place.
  OverlayRequests build(const OverlayModel& model, ViewSettings& settings);
  // Records the overlay's render pass on the swapchain image, which arrives in TRANSFER_DST_OPTIMAL
  // (after the blit) and leaves in PRESENT_SRC_KHR.
  void record(const vk::raii::CommandBuffer& cmd, std::uint32_t imageIndex);
  // The direct path's alternative: draws the panel (nothing when hidden) on the cleared layer, which
  // is left in SHADER_READ_ONLY_OPTIMAL for the resolve pass, but only when its draw data differ
  // from what the layer holds (most frames differ in nothing: the figures change twice a second).
  // Returns whether it recorded the pass. Later frames' passes wait for earlier frames' reads.
  bool recordLayer(const vk::raii::CommandBuffer& cmd);
  vk::ImageView layerView() const { return *layer_.view; }

  bool visible = true;

private:
  // Each ImGui init step is undone by its own scope object, so a throw halfway leaks nothing.
  struct ImGuiScope {
    ImGuiScope();
    ~ImGuiScope();
  };
  struct GlfwBackendScope {
    explicit GlfwBackendScope(const Window& window);
    ~GlfwBackendScope();
  };
  struct VulkanBackendScope {
    VulkanBackendScope(const vulkan::Context& context, vk::DescriptorPool pool, vk::RenderPass pass,
                       std::uint32_t imageCount);
    ~VulkanBackendScope();
  };

  const vulkan::Context& context_;
  vk::Extent2D extent_{0, 0};
  // Vulkan objects first: the backend scopes below are destroyed before them.
  vk::raii::RenderPass renderPass_{nullptr};
  vk::raii::RenderPass layerPass_{nullptr}; // the same attachment format: ImGui's pipeline fits both
  vk::raii::DescriptorPool pool_{nullptr};
  std::vector<vk::raii::Framebuffer> framebuffers_;
  DeviceImage layer_;
  vk::raii::Framebuffer layerFramebuffer_{nullptr};
  std::vector<unsigned char> layerDrawn_; // the draw data the layer holds (drawDataBytes)
  bool layerValid_ = false;               // false until drawn after (re-)creation
  ImGuiScope imgui_;
  std::unique_ptr<GlfwBackendScope> glfwBackend_;
  std::unique_ptr<VulkanBackendScope> vulkanBackend_;
};

} // namespace vkray
