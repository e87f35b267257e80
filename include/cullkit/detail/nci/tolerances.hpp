// cullkit/detail/nci/tolerances.hpp: the named margins of the NormalClassIndex's arithmetic.
// Each one only ever makes a test keep more (a ray unfinished longer, a cell, class or triangle
// kept, a rectangle grown): changing one changes the work done, never a pixel's answer, as long
// as it still covers the rounding it is named for.
#pragma once

namespace cullkit::detail::nci::tolerance {

// Relative error of a value computed in float, or from float inputs, and then used in double:
// a few float roundings (2^-24, about 6e-8, each) with more than a factor 10 to spare. Covers the
// ray slopes across the walk axis, the reach of a ray's hit along it, the box exit parameter
// and the depth bound of a box along a ray.
inline constexpr double float_relative = 1e-6;
inline constexpr float float_relative_f = 1e-6f;

// A ray whose walk-axis component is below this (directions are unit length) is treated as
// parallel to the slices: its slopes would be too large to bound a beam, so the beam covers the
// whole slice while it lives.
inline constexpr double flat_direction = 1e-6;

// Angular margin in radians added to a normal class's cone and to a tile's cone of rays: the
// normals are float, the cone axes averaged, the ray directions float.
inline constexpr double cone_angle = 2e-3;

// Margin of the cosine comparison that skips a class facing away from a whole tile: the products
// of the float cone sines and cosines, in double.
inline constexpr double cone_skip = 1e-6;

// Relative widening of a ray's entry and exit of the scene box: double rounding of the slab
// products, far below the box's own inflation.
inline constexpr double box_crossing = 1e-9;

// Screen rectangles are used only when the pixel rays' target point keeps its homogeneous w this
// far (relative) from the sign switch PixelRays makes between the far and the near plane, so that
// every pixel of the screen is on the same side of the switch.
inline constexpr double target_plane_switch = 1e-6;

}  // namespace cullkit::detail::nci::tolerance
