// The Dear ImGui overlay (see overlay.h). The GLFW and Vulkan backends are Debian's libimgui-dev
// sources, compiled into the viewer by CMakeLists.txt.
#include "viewer/overlay.h"

#include <array>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <functional>

#include <imgui.h>
#include <imgui_impl_glfw.h>
#include <imgui_impl_vulkan.h>

#include "scene/scene_limits.h"
#include "util/error.h"

namespace vkray {

namespace {

void checkOverlayResult(VkResult result) {
  if (result < 0) throw DeviceError("drawing the overlay: " + vk::to_string(static_cast<vk::Result>(result)));
}

// A rate as "12.3 M".
std::string mega(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2f M", v * 1e-6);
  return buf;
}

template <typename E>
bool comboEnum(const char* label, E& value, std::initializer_list<std::pair<E, const char*>> items) {
  const char* current = "";
  for (const auto& [v, name] : items)
    if (v == value) current = name;
  bool changed = false;
  if (ImGui::BeginCombo(label, current)) {
    for (const auto& [v, name] : items) {
      if (ImGui::Selectable(name, v == value) && v != value) {
        value = v;
        changed = true;
      }
    }
    ImGui::EndCombo();
  }
  return changed;
}

// The same for an enum with a name table (util/enum_names.h).
template <typename E> bool comboEnum(const char* label, E& value) {
  const char* current = "";
  for (const auto& entry : EnumNames<E>::values)
    if (entry.value == value) current = entry.name.data();
  bool changed = false;
  if (ImGui::BeginCombo(label, current)) {
    for (const auto& entry : EnumNames<E>::values) {
      if (ImGui::Selectable(entry.name.data(), entry.value == value) && entry.value != value) {
        value = entry.value;
        changed = true;
      }
    }
    ImGui::EndCombo();
  }
  return changed;
}

// Everything ImGui_ImplVulkan_RenderDrawData draws from, as bytes: equal bytes, equal pixels.
void drawDataBytes(const ImDrawData* data, bool visible, std::vector<unsigned char>& out) {
  out.clear();
  auto put = [&out](const void* p, std::size_t n) {
    const auto* bytes = static_cast<const unsigned char*>(p);
    out.insert(out.end(), bytes, bytes + n);
  };
  if (!visible || data == nullptr) return;
  put(&data->DisplayPos, sizeof data->DisplayPos);
  put(&data->DisplaySize, sizeof data->DisplaySize);
  put(&data->FramebufferScale, sizeof data->FramebufferScale);
  for (int i = 0; i < data->CmdListsCount; ++i) {
    const ImDrawList* list = data->CmdLists[i];
    put(list->VtxBuffer.Data, sizeof(ImDrawVert) * static_cast<std::size_t>(list->VtxBuffer.Size));
    put(list->IdxBuffer.Data, sizeof(ImDrawIdx) * static_cast<std::size_t>(list->IdxBuffer.Size));
    for (const ImDrawCmd& c : list->CmdBuffer) {
      put(&c.ClipRect, sizeof c.ClipRect);
      put(&c.TextureId, sizeof c.TextureId);
      put(&c.VtxOffset, sizeof c.VtxOffset);
      put(&c.IdxOffset, sizeof c.IdxOffset);
      put(&c.ElemCount, sizeof c.ElemCount);
      put(&c.UserCallback, sizeof c.UserCallback);
    }
  }
}

} // namespace

Overlay::ImGuiScope::ImGuiScope() {
  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGui::GetIO().IniFilename = nullptr; // no imgui.ini left in the working directory
  ImGui::StyleColorsDark();
}

Overlay::ImGuiScope::~ImGuiScope() {
  ImGui::DestroyContext();
}

Overlay::GlfwBackendScope::GlfwBackendScope(const Window& window) {
  // Chains to the window's own callbacks, installed before.
  if (!ImGui_ImplGlfw_InitForVulkan(window.handle(), true)) throw Error("the overlay's GLFW backend failed to start");
}

Overlay::GlfwBackendScope::~GlfwBackendScope() {
  ImGui_ImplGlfw_Shutdown();
}

Overlay::VulkanBackendScope::VulkanBackendScope(const vulkan::Context& context, vk::DescriptorPool pool,
                                                vk::RenderPass pass, std::uint32_t imageCount) {
  ImGui_ImplVulkan_InitInfo info{};
  info.Instance = *context.instance();
  info.PhysicalDevice = *context.physicalDevice();
  info.Device = *context.device();
  info.QueueFamily = context.queueFamily();
  info.Queue = *context.queue();
  info.DescriptorPool = pool;
  info.Subpass = 0;
  // ImageCount sizes the backend's ring of vertex buffers, one per frame in flight.
  info.MinImageCount = imageCount;
  info.ImageCount = imageCount;
  info.MSAASamples = VK_SAMPLE_COUNT_1_BIT;
  info.CheckVkResultFn = checkOverlayResult;
  if (!ImGui_ImplVulkan_Init(&info, pass)) throw DeviceError("the overlay's Vulkan backend failed to start");
  try {
    context.submitAndWait("uploading the overlay's font",
                          [](const vk::raii::CommandBuffer& cmd) { ImGui_ImplVulkan_CreateFontsTexture(*cmd); });
  } catch (...) {
    ImGui_ImplVulkan_Shutdown();
    throw;
  }
  ImGui_ImplVulkan_DestroyFontUploadObjects();
}

Overlay::VulkanBackendScope::~VulkanBackendScope() {
  ImGui_ImplVulkan_Shutdown();
}

Overlay::Overlay(const vulkan::Context& context, const Window& window, const Swapchain& swapchain) : context_(context) {
  const auto& device = context.device();
  vulkan::vulkanStep("creating the overlay's render pass", [&] {
    vk::AttachmentDescription color({}, swapchain.format(), vk::SampleCountFlagBits::e1, vk::AttachmentLoadOp::eLoad,
                                    vk::AttachmentStoreOp::eStore, vk::AttachmentLoadOp::eDontCare,
                                    vk::AttachmentStoreOp::eDontCare, vk::ImageLayout::eTransferDstOptimal,
                                    vk::ImageLayout::ePresentSrcKHR);
    vk::AttachmentReference ref(0, vk::ImageLayout::eColorAttachmentOptimal);
    vk::SubpassDescription subpass({}, vk::PipelineBindPoint::eGraphics, {}, ref);
    // The two passes differ only in their attachment's load operation and layouts, so that ImGui's
    // one pipeline fits both (render-pass compatibility); their dependencies are the same pair,
    // covering both uses. In: the blit's writes (swapchain pass), or the earlier frames' resolve
    // reads of the layer (layer pass), before the attachment is loaded or cleared and drawn on.
    // Out: the layer's drawing before the resolve pass reads it.
    std::array<vk::SubpassDependency, 2> deps{
        vk::SubpassDependency(VK_SUBPASS_EXTERNAL, 0,
                              vk::PipelineStageFlagBits::eTransfer | vk::PipelineStageFlagBits::eComputeShader,
                              vk::PipelineStageFlagBits::eColorAttachmentOutput, vk::AccessFlagBits::eTransferWrite,
                              vk::AccessFlagBits::eColorAttachmentRead | vk::AccessFlagBits::eColorAttachmentWrite),
        vk::SubpassDependency(0, VK_SUBPASS_EXTERNAL, vk::PipelineStageFlagBits::eColorAttachmentOutput,
                              vk::PipelineStageFlagBits::eComputeShader, vk::AccessFlagBits::eColorAttachmentWrite,
                              vk::AccessFlagBits::eShaderRead)};
    // Swapchain pass: the blit has written the picture; keep it (LOAD), draw on top, hand it to present.
    renderPass_ = vk::raii::RenderPass(device, vk::RenderPassCreateInfo({}, color, subpass, deps));
    // Layer pass: cleared to transparent, drawn on, read by the resolve pass that follows.
    vk::AttachmentDescription layer({}, swapchain.format(), vk::SampleCountFlagBits::e1, vk::AttachmentLoadOp::eClear,
                                    vk::AttachmentStoreOp::eStore, vk::AttachmentLoadOp::eDontCare,
                                    vk::AttachmentStoreOp::eDontCare, vk::ImageLayout::eUndefined,
                                    vk::ImageLayout::eShaderReadOnlyOptimal);
    layerPass_ = vk::raii::RenderPass(device, vk::RenderPassCreateInfo({}, layer, subpass, deps));
    // The backend needs one combined image sampler (the font atlas).
    vk::DescriptorPoolSize size(vk::DescriptorType::eCombinedImageSampler, 4);
    pool_ = vk::raii::DescriptorPool(
        device, vk::DescriptorPoolCreateInfo(vk::DescriptorPoolCreateFlagBits::eFreeDescriptorSet, 4, size));
  });
  attach(swapchain);
  glfwBackend_ = std::make_unique<GlfwBackendScope>(window);
  vulkanBackend_ = std::make_unique<VulkanBackendScope>(context, *pool_, *renderPass_, 2);
}

Overlay::~Overlay() = default;

void Overlay::attach(const Swapchain& swapchain) {
  framebuffers_.clear();
  extent_ = swapchain.extent();
  vulkan::vulkanStep("creating the overlay's framebuffers", [&] {
    for (std::uint32_t i = 0; i < swapchain.imageCount(); ++i) {
      vk::ImageView view = swapchain.view(i);
      framebuffers_.emplace_back(context_.device(),
                                 vk::FramebufferCreateInfo({}, *renderPass_, view, extent_.width, extent_.height, 1));
    }
    layerFramebuffer_ = vk::raii::Framebuffer(nullptr);
    layer_ = DeviceImage();
    layer_ = makeDeviceImage(context_, swapchain.format(),
                             vk::ImageUsageFlagBits::eColorAttachment | vk::ImageUsageFlagBits::eSampled, extent_);
    layerFramebuffer_ = vk::raii::Framebuffer(
        context_.device(), vk::FramebufferCreateInfo({}, *layerPass_, *layer_.view, extent_.width, extent_.height, 1));
  });
  layerValid_ = false;
}

void Overlay::newFrame() {
  ImGui_ImplVulkan_NewFrame();
  ImGui_ImplGlfw_NewFrame();
  ImGui::NewFrame();
}

bool Overlay::wantsMouse() const {
  return visible && ImGui::GetIO().WantCaptureMouse;
}

bool Overlay::wantsKeyboard() const {
  return visible && ImGui::GetIO().WantCaptureKeyboard;
}

namespace {

// A ray's colour over the image and in the list: eye white, reflection cyan, refraction magenta,
// shadow yellow when it reaches its light and dark red when it is blocked.
ImU32 rayColour(const InspectedRay& r) {
  switch (r.kind) {
  case TreeRayKind::Eye:
    return IM_COL32(255, 255, 255, 255);
  case TreeRayKind::Reflection:
    return IM_COL32(64, 224, 255, 255);
  case TreeRayKind::Refraction:
    return IM_COL32(255, 96, 255, 255);
  case TreeRayKind::Shadow:
    return r.outcome == TreeOutcome::Blocked ? IM_COL32(200, 40, 30, 255) : IM_COL32(255, 220, 60, 255);
  }
  return IM_COL32(255, 255, 255, 255);
}

// The segment a ray travelled, in world space: to what it met, or far along it into the background.
std::pair<glm::dvec3, glm::dvec3> raySegment(const InspectedRay& r, double far) {
  if (r.outcome == TreeOutcome::Background) return {r.origin, r.origin + far * r.direction};
  return {r.origin, r.point};
}

// Draws each ray of the tree as a line over the image: world points projected with the camera onto
// the image plane, cut where they pass behind the eye, scaled from render pixels to the window.
void drawRayLines(const RayTree& tree, const CameraFrame& cam, vk::Extent2D renderSize) {
  ImDrawList* draw = ImGui::GetBackgroundDrawList();
  const ImVec2 display = ImGui::GetIO().DisplaySize;
  const double sx = display.x, sy = display.y;
  const glm::dvec3 right = cam.right * (cam.tanHalfFovY * cam.aspect), up = cam.up * cam.tanHalfFovY;
  const double near = 1e-3;
  auto depth = [&](const glm::dvec3& p) { return glm::dot(p - cam.position, cam.forward); };
  auto project = [&](const glm::dvec3& p) {
    glm::dvec3 d = p - cam.position;
    double z = glm::dot(d, cam.forward);
    double x = glm::dot(d, right) / (glm::dot(right, right) * z);
    double y = glm::dot(d, up) / (glm::dot(up, up) * z);
    return ImVec2(static_cast<float>((x + 1.0) * 0.5 * sx), static_cast<float>((1.0 - y) * 0.5 * sy));
  };
  double scale = 1.0; // the scene's size: rays into the background are drawn this far
  for (const InspectedRay& r : tree.rays) scale = std::max(scale, r.distance);
  for (const InspectedRay& r : tree.rays) {
    auto [a, b] = raySegment(r, 10.0 * scale);
    double za = depth(a), zb = depth(b);
    if (za < near && zb < near) continue;
    // Cut at the near plane: the part behind the eye has no image.
    if (za < near) a = a + (b - a) * ((near - za) / (zb - za));
    if (zb < near) b = a + (b - a) * ((near - depth(a)) / (zb - depth(a)));
    const float width = r.kind == TreeRayKind::Shadow ? 1.0f : 2.0f;
    draw->AddLine(project(a), project(b), rayColour(r), width);
    if (r.outcome == TreeOutcome::Surface || r.outcome == TreeOutcome::Blocked)
      draw->AddCircleFilled(project(b), 3.0f, rayColour(r));
  }
  // The inspected pixel itself.
  const float px = (tree.pixel.x + 0.5f) * display.x / static_cast<float>(renderSize.width);
  const float py = (tree.pixel.y + 0.5f) * display.y / static_cast<float>(renderSize.height);
  draw->AddRect(ImVec2(px - 4, py - 4), ImVec2(px + 4, py + 4), IM_COL32(255, 255, 255, 255), 0.0f, 0, 1.5f);
}

std::string rgb(const glm::dvec3& c) {
  char text[64];
  std::snprintf(text, sizeof text, "%.4f %.4f %.4f", c.x, c.y, c.z);
  return text;
}

// One line per ray: what it is, what it met and what it added; children nested under their parent.
void listRays(const RayTree& tree) {
  std::vector<std::vector<std::size_t>> children(tree.rays.size());
  std::vector<std::size_t> roots;
  for (std::size_t i = 0; i < tree.rays.size(); ++i) {
    if (tree.rays[i].parent)
      children[*tree.rays[i].parent].push_back(i);
    else
      roots.push_back(i);
  }
  std::function<void(std::size_t)> node = [&](std::size_t i) {
    const InspectedRay& r = tree.rays[i];
    std::string met;
    switch (r.outcome) {
    case TreeOutcome::Background:
      met = "background";
      break;
    case TreeOutcome::Surface:
    case TreeOutcome::Blocked: {
      const char* kinds[] = {"sphere", "plane", "polygon", "triangle", "mesh"};
      met = (r.outcome == TreeOutcome::Blocked ? "blocked by " : "") +
            std::string(r.object ? kinds[static_cast<int>(r.object->kind)] : "?") + " " +
            (r.object ? std::to_string(r.object->index) : "");
      break;
    }
    case TreeOutcome::Light:
    case TreeOutcome::Unshadowed:
      met = "light " + std::to_string(r.light.value_or(0));
      break;
    }
    char label[256];
    std::snprintf(label, sizeof label, "#%zu %s -> %s%s##ray%zu", i, enumName(r.kind).data(), met.c_str(),
                  r.cuts != 0 ? " (cut)" : "", i);
    ImGui::PushStyleColor(ImGuiCol_Text, rayColour(r));
    const ImGuiTreeNodeFlags flags =
        ImGuiTreeNodeFlags_DefaultOpen | (children[i].empty() ? ImGuiTreeNodeFlags_Leaf : ImGuiTreeNodeFlags_None);
    const bool open = ImGui::TreeNodeEx(label, flags);
    ImGui::PopStyleColor();
    if (ImGui::IsItemHovered()) {
      ImGui::SetTooltip("weight       %s\ncontribution %s\ndistance     %.4g", rgb(r.weight).c_str(),
                        rgb(r.contribution).c_str(), r.distance);
    }
    if (open) {
      for (std::size_t c : children[i]) node(c);
      ImGui::TreePop();
    }
  };
  for (std::size_t root : roots) node(root);
}

} // namespace

OverlayRequests Overlay::build(const OverlayModel& m, ViewSettings& settings) {
  OverlayRequests req;
  if (!visible) {
    ImGui::Render();
    return req;
  }
  ImGui::SetNextWindowPos(ImVec2(8, 8), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowSize(ImVec2(340, 0), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowBgAlpha(0.8f);
  ImGui::Begin("vkray", nullptr, ImGuiWindowFlags_NoFocusOnAppearing);

  ImGui::TextUnformatted(m.scenePath.c_str());
  ImGui::TextUnformatted(m.device.c_str());
  ImGui::TextUnformatted(m.presentMode.c_str());
  ImGui::Text("%ux%u, %u samples/pixel", m.renderSize.width, m.renderSize.height, m.samples);
  if (!m.reloadError.empty()) {
    ImGui::PushStyleColor(ImGuiCol_Text, ImVec4(1.0f, 0.45f, 0.4f, 1.0f));
    ImGui::TextWrapped("reload failed, showing the last good scene: %s", m.reloadError.c_str());
    ImGui::PopStyleColor();
  }
  if (!m.status.empty()) ImGui::TextWrapped("%s", m.status.c_str());

  if (m.rayTree) drawRayLines(*m.rayTree, m.camera, m.renderSize);
  if (m.rayTree && ImGui::CollapsingHeader("Ray tree", ImGuiTreeNodeFlags_DefaultOpen)) {
    const RayTree& t = *m.rayTree;
    ImGui::Text("pixel %u,%u: %zu rays", t.pixel.x, t.pixel.y, t.rays.size());
    ImGui::Text("value %s", rgb(t.value).c_str());
    ImGui::SameLine();
    if (ImGui::SmallButton("close")) req.closeRayTree = true;
    ImGui::BeginChild("rays", ImVec2(0, std::min(24.0f * static_cast<float>(t.rays.size()) + 8.0f, 260.0f)), true);
    listRays(t);
    ImGui::EndChild();
  }
  if (ImGui::CollapsingHeader("Convergence", ImGuiTreeNodeFlags_DefaultOpen)) {
    // The block estimate of each pixel's standard error (convergence.h), linear, the largest of
    // R, G and B; converged: 0.8 of its own square and 0.2 of its 3 x 3 mean square at most the threshold squared.
    const ConvergenceFigures& c = m.convergence;
    if (!c.measured) {
      ImGui::TextDisabled("error: measuring...");
    } else if (!c.estimated()) {
      ImGui::TextDisabled("error: needs 2 samples/pixel");
    } else {
      ImGui::Text("error    mean %.2e  p95 %.2e", c.errorMean, c.errorP95);
      ImGui::Text("converged %5.1f %% (at %u samples/pixel)", 100.0 * c.converged, c.samples);
    }
    ImGui::Text("threshold %.3g%s", m.noiseThreshold, m.defaultThreshold ? " (default; --noise-threshold)" : "");
    comboEnum("display (M)", settings.display);
    if (m.display == DisplayMode::Error) {
      ImGui::TextWrapped("error map, log scale: blue %.1e .. red %.1e (threshold: green), black 0, "
                         "white above or no estimate",
                         m.noiseThreshold / 10.0, m.noiseThreshold * 10.0);
    } else if (m.display == DisplayMode::Cost) {
      ImGui::TextWrapped("cost map, rays per sample, log scale: blue %.0f .. red %.0f, white above", kCostMapLow,
                         kCostMapHigh);
    }
  }
  if (ImGui::CollapsingHeader("Timing", ImGuiTreeNodeFlags_DefaultOpen)) {
    ImGui::Text("frame    %7.2f ms  (%.1f fps)", m.frameMs, m.frameMs > 0 ? 1000.0 / m.frameMs : 0.0);
    ImGui::Text("trace    %7.2f ms  GPU", m.traceMs);
    ImGui::Text("resolve  %7.2f ms  GPU", m.resolveMs);
    ImGui::Text("blit     %7.2f ms  GPU", m.blitMs);
    ImGui::Text("overlay  %7.2f ms  GPU", m.overlayMs);
    ImGui::Text("host     %7.2f ms  CPU", m.hostMs);
    if (settings.countStats) ImGui::Text("rays/s   %s", mega(m.raysPerSecond).c_str());
  }
  if (settings.countStats && ImGui::CollapsingHeader("Rays per frame", ImGuiTreeNodeFlags_DefaultOpen)) {
    const RayStats& s = m.raysPerFrame;
    auto row = [](std::string_view name, std::uint64_t v) {
      ImGui::Text("%-18.*s %12" PRIu64, static_cast<int>(name.size()), name.data(), v);
    };
    for (const auto& [name, value] : s.named()) row(name, value);
    row("rays", s.total());
  }
  if (ImGui::CollapsingHeader("Features")) {
    for (const auto& line : m.features) ImGui::TextWrapped("%s", line.c_str());
  }
  if (ImGui::CollapsingHeader("Settings", ImGuiTreeNodeFlags_DefaultOpen)) {
    RenderSettings& r = settings.render;
    ImGui::SliderInt("max depth", &r.maxDepth, 0, 16);
    float bailout = static_cast<float>(r.bailout);
    if (ImGui::SliderFloat("bailout", &bailout, 0.0f, 0.5f, "%.4f", ImGuiSliderFlags_Logarithmic)) r.bailout = bailout;
    ImGui::SliderInt("samples/frame", &settings.samplesPerFrame, 1, 16);
    int maxSamples = static_cast<int>(settings.maxSamples);
    if (ImGui::InputInt("max samples", &maxSamples, 64, 1024))
      settings.maxSamples = static_cast<std::uint32_t>(std::clamp<long long>(maxSamples, 1, kMaxSpp * 16));
    comboEnum("numerics", r.numerics);
    comboEnum("fresnel", r.fresnel);
    comboEnum("glass shadows", r.transmissiveShadows);
    comboEnum("texture filter", r.textureFilter);
    comboEnum("resolution", settings.renderScale, {{1.0, "100 %"}, {0.5, "50 %"}, {0.25, "25 %"}});
    comboEnum("while moving", settings.motionScale, {{1.0, "100 %"}, {0.5, "50 %"}, {0.25, "25 %"}});
    ImGui::Checkbox("shadows", &settings.effects.shadows);
    ImGui::SameLine();
    ImGui::Checkbox("reflection", &settings.effects.reflection);
    ImGui::Checkbox("refraction", &settings.effects.refraction);
    ImGui::SameLine();
    ImGui::Checkbox("checker", &settings.effects.checker);
    ImGui::Checkbox("count rays", &settings.countStats);
    ImGui::SameLine();
    ImGui::TextDisabled("(in 1 frame of %u)", kRayCountEvery);
  }
  if (ImGui::CollapsingHeader("Camera", ImGuiTreeNodeFlags_DefaultOpen)) {
    bool fly = m.cameraMode == CameraMode::Fly;
    if (ImGui::RadioButton("orbit", !fly) && fly) req.toggleFly = true;
    ImGui::SameLine();
    if (ImGui::RadioButton("fly (F)", fly) && !fly) req.toggleFly = true;
    if (ImGui::Button("reset (R)")) req.resetCamera = true;
    ImGui::SameLine();
    if (ImGui::Button("save camera (C)")) req.saveCamera = true;
    ImGui::SameLine();
    if (ImGui::Button("screenshot (P)")) req.screenshot = true;
    ImGui::TextWrapped("%s", m.cameraJson.c_str());
  }
  if (ImGui::CollapsingHeader("Controls")) {
    ImGui::TextUnformatted("left drag: orbit (fly: look)\n"
                           "right/middle drag, shift+left: pan\n"
                           "wheel: zoom\n"
                           "F / Tab: fly mode; W A S D, Q E: move, shift: fast\n"
                           "R: reset camera   C: save camera JSON\n"
                           "M: display image / error map / cost map\n"
                           "click: the pixel's ray tree (drawn and listed)\n"
                           "P / F12: screenshot   H / F1: overlay   Esc: quit");
  }
  ImGui::End();
  ImGui::Render();
  return req;
}

void Overlay::record(const vk::raii::CommandBuffer& cmd, std::uint32_t imageIndex) {
  vk::RenderPassBeginInfo begin(*renderPass_, *framebuffers_[imageIndex], vk::Rect2D({0, 0}, extent_));
  cmd.beginRenderPass(begin, vk::SubpassContents::eInline);
  ImDrawData* data = ImGui::GetDrawData();
  if (visible && data != nullptr && data->CmdListsCount > 0) ImGui_ImplVulkan_RenderDrawData(data, *cmd);
  cmd.endRenderPass();
}

bool Overlay::recordLayer(const vk::raii::CommandBuffer& cmd) {
  ImDrawData* data = ImGui::GetDrawData();
  std::vector<unsigned char> now;
  drawDataBytes(data, visible, now);
  if (layerValid_ && now == layerDrawn_) return false;
  vk::ClearValue transparent(vk::ClearColorValue(std::array<float, 4>{0.0f, 0.0f, 0.0f, 0.0f}));
  vk::RenderPassBeginInfo begin(*layerPass_, *layerFramebuffer_, vk::Rect2D({0, 0}, extent_), transparent);
  cmd.beginRenderPass(begin, vk::SubpassContents::eInline);
  if (visible && data != nullptr && data->CmdListsCount > 0) ImGui_ImplVulkan_RenderDrawData(data, *cmd);
  cmd.endRenderPass();
  layerDrawn_ = std::move(now);
  layerValid_ = true;
  return true;
}

} // namespace vkray
