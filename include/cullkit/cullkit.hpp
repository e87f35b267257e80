// cullkit/cullkit.hpp: the umbrella header. Include this, or only the headers you use.
#pragma once

#include "config.hpp"
#include "geometry.hpp"
#include "traits.hpp"
#include "box_proxy.hpp"
#include "adaptive_binary_tree.hpp"
#include "occlusion_tree.hpp"
#include "occlusion_culling.hpp"
#include "normal_class_index.hpp"
#include "mesh_occlusion_culler.hpp"
