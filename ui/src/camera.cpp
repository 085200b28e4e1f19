#include "ui/camera.h"

#include <algorithm>
#include <cmath>
#include <glm/gtc/constants.hpp>
#include <glm/gtc/matrix_transform.hpp>

namespace spacetime::ui {

glm::vec3 OrbitCamera::eye() const {
  const glm::vec3 back(std::sin(yaw) * std::cos(pitch), std::sin(pitch), std::cos(yaw) * std::cos(pitch));
  return target + distance * back;
}

glm::mat4 OrbitCamera::view() const { return glm::lookAt(eye(), target, glm::vec3(0, 1, 0)); }

float OrbitCamera::visibleHeight() const { return 2.0f * distance * std::tan(fovY / 2); }

glm::mat4 OrbitCamera::projection(float aspect) const {
  const float nearZ = std::max(1e-3f, distance * 0.01f), farZ = distance * 100.0f + 10.0f;
  if (!orthographic) return glm::perspective(fovY, aspect, nearZ, farZ);
  const float h = visibleHeight() / 2, w = h * aspect;
  return glm::ortho(-w, w, -h, h, -farZ, farZ);
}

void OrbitCamera::orbit(float dYaw, float dPitch) {
  yaw += dYaw;
  pitch = std::clamp(pitch + dPitch, -glm::half_pi<float>() + 1e-3f, glm::half_pi<float>() - 1e-3f);
}

void OrbitCamera::pan(float dx, float dy) {
  const glm::mat4 v = view();
  const glm::vec3 right(v[0][0], v[1][0], v[2][0]), up(v[0][1], v[1][1], v[2][1]);
  target += visibleHeight() * (-dx * right + dy * up);
}

void OrbitCamera::zoom(float factor) { distance = std::clamp(distance * factor, 0.05f, 500.0f); }

void OrbitCamera::frame(const glm::vec3& lo, const glm::vec3& hi) {
  target = (lo + hi) * 0.5f;
  const float radius = std::max(0.1f, glm::length(hi - lo) * 0.5f);
  distance = radius * 1.15f / std::sin(fovY / 2);
}

void OrbitCamera::ray(float x, float y, float width, float height, glm::vec3* origin,
                      glm::vec3* direction) const {
  const glm::mat4 inv = glm::inverse(projection(width / std::max(1.0f, height)) * view());
  const float nx = 2 * x / width - 1, ny = 1 - 2 * y / height;
  glm::vec4 a = inv * glm::vec4(nx, ny, -1, 1), b = inv * glm::vec4(nx, ny, 1, 1);
  a /= a.w;
  b /= b.w;
  *origin = glm::vec3(a);
  *direction = glm::normalize(glm::vec3(b - a));
}

glm::vec2 OrbitCamera::project(const glm::vec3& p, float width, float height) const {
  glm::vec4 c = projection(width / std::max(1.0f, height)) * view() * glm::vec4(p, 1);
  c /= c.w;
  return {(c.x + 1) * 0.5f * width, (1 - c.y) * 0.5f * height};
}

}  // namespace spacetime::ui
