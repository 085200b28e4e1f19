// The viewport camera: an orbit camera around a target (Blender's turntable), with
// perspective or orthographic projection, preset views and frame-all. Pure GLM math, no GL.
#pragma once

#include <glm/glm.hpp>
#include <glm/gtc/constants.hpp>

namespace spacetime::ui {

class OrbitCamera {
 public:
  glm::vec3 target{0.3f, 0.25f, 0.0f};
  float distance = 2.5f;
  float yaw = 0.0f;    // radians about world y; 0 looks along -z (the front view)
  float pitch = 0.15f; // radians above the horizon
  bool orthographic = false;
  float fovY = glm::radians(35.0f);

  glm::vec3 eye() const;
  glm::mat4 view() const;
  glm::mat4 projection(float aspect) const;

  void orbit(float dYaw, float dPitch);
  // Moves the target in the view plane by a fraction of the visible height.
  void pan(float dxFraction, float dyFraction);
  void zoom(float factor);  // distance *= factor
  void frame(const glm::vec3& boundsMin, const glm::vec3& boundsMax);
  void front() { yaw = 0; pitch = 0; }
  void side() { yaw = glm::half_pi<float>(); pitch = 0; }
  void top() { yaw = 0; pitch = glm::half_pi<float>() - 1e-3f; }

  // A world ray through a pixel (x right, y down) of a viewport of the given size.
  void ray(float x, float y, float width, float height, glm::vec3* origin, glm::vec3* direction) const;
  // Pixel coordinates of a world point (y down).
  glm::vec2 project(const glm::vec3& p, float width, float height) const;

 private:
  float visibleHeight() const;  // at the target's distance
};

}  // namespace spacetime::ui
