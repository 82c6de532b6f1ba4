// The caller's rays as raycast.comp and direction_order.comp read them (VKRAY_RAY_INPUT_CALLER_DIRECTIONS):
// six doubles a ray as the caller gave them, three RGBA32UI texels, fetched by CALLER_RAY_TEXEL(index),
// which the includer defines.

// Whether ray k leaves from the first ray's origin, bit for bit (the host checked that one and sends
// it as the camera's), with a direction that has one: then `direction` is that direction made a unit
// vector in double as unit_vector does on the host (the largest magnitude divided out first outside
// [2^-480, 2^480]), rounded to float; else (0, 0, 1), and the host casts the ray.
bool caller_unit_direction(int k, out vec3 direction) {
  uvec4 origin_xy = CALLER_RAY_TEXEL(3 * k), origin_z_x = CALLER_RAY_TEXEL(3 * k + 1);
  uvec4 direction_yz = CALLER_RAY_TEXEL(3 * k + 2);
  dvec3 given = dvec3(packDouble2x32(origin_z_x.zw), packDouble2x32(direction_yz.xy), packDouble2x32(direction_yz.zw));
  double scale = max(max(abs(given.x), abs(given.y)), abs(given.z));
  bool finite = !any(isnan(given)) && !any(isinf(given));
  bool traceable = origin_xy == CALLER_RAY_TEXEL(0) && origin_z_x.xy == CALLER_RAY_TEXEL(1).xy && finite && scale > 0.0LF;
  if (scale <= ldexp(1.0LF, -480) || scale >= ldexp(1.0LF, 480)) given /= scale;
  direction = traceable ? vec3(given * (1.0LF / sqrt(dot(given, given)))) : vec3(0.0, 0.0, 1.0);
  return traceable;
}
