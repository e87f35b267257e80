// cullkit/cullkit.hpp: the umbrella header. Include this, or only the headers you use.
#pragma once

#include "config.hpp"
#include "geometry.hpp"
#include "traits.hpp"
#include "mesh_buffers.hpp"
#include "box_proxy.hpp"
#include "adaptive_binary_tree.hpp"
#include "occlusion_tree.hpp"
#include "occlusion_culling.hpp"
#include "normal_class_index.hpp"
#include "depth_sort.hpp"
#include "bsp_tree.hpp"
#include "portal_graph.hpp"
#include "mesh_occlusion_culler.hpp"
