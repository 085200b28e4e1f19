#version 330 core
// Lit solids: unit meshes placed by a model matrix (which may scale non-uniformly).
layout(location = 0) in vec3 position;
layout(location = 1) in vec3 normal;
uniform mat4 model;
uniform mat4 viewProjection;
uniform mat3 normalMatrix;  // inverse transpose of the model's upper 3x3
out vec3 worldNormal;
out vec3 worldPosition;
void main() {
  vec4 p = model * vec4(position, 1.0);
  worldPosition = p.xyz;
  worldNormal = normalMatrix * normal;
  gl_Position = viewProjection * p;
}
