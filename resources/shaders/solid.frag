#version 330 core
// Blinn-Phong with a key light from above-front and a camera headlight, plus hemisphere ambient.
in vec3 worldNormal;
in vec3 worldPosition;
uniform vec4 color;
uniform vec3 eye;
out vec4 fragColor;
void main() {
  vec3 n = normalize(worldNormal);
  vec3 v = normalize(eye - worldPosition);
  if (dot(n, v) < 0.0) n = -n;
  vec3 key = normalize(vec3(0.4, 1.0, 0.6));
  float diffuse = 0.55 * max(dot(n, key), 0.0) + 0.35 * max(dot(n, v), 0.0);
  float ambient = mix(0.18, 0.32, 0.5 + 0.5 * n.y);
  float specular = 0.25 * pow(max(dot(n, normalize(key + v)), 0.0), 40.0);
  fragColor = vec4(color.rgb * (ambient + diffuse) + vec3(specular), color.a);
}
