// cullkit/geometry.hpp: all value types of the geometry core.
#pragma once

#include "geometry/aabb.hpp"
#include "geometry/camera.hpp"
#include "geometry/convex_polygon.hpp"
#include "geometry/convex_volume.hpp"
#include "geometry/frustum.hpp"
#include "geometry/plane.hpp"
#include "geometry/shadow_caster_volume.hpp"
#include "geometry/sphere.hpp"
#include "geometry/transform_bounds.hpp"
