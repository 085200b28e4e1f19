#version 330 core
// Unlit lines (grid, trails): world positions with a per-vertex colour.
layout(location = 0) in vec3 position;
layout(location = 1) in vec4 color;
uniform mat4 viewProjection;
out vec4 vertexColor;
void main() {
  vertexColor = color;
  gl_Position = viewProjection * vec4(position, 1.0);
}
