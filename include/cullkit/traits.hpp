// cullkit/traits.hpp: how cullkit reads your vertex and object types.
//
// Two ways to plug in your data:
//  * Traits: specialize `cullkit::VertexTraits<YourVertex>` with
//        static glm::vec3 position(const YourVertex&);
//    or `cullkit::BoundsTraits<YourObject>` with
//        static cullkit::Aabb bounds(const YourObject&);
//    The primary templates are empty, so a missing specialization is reported at compile time by a
//    static_assert that names your type (see `require_vertex_traits`, `require_bounds_traits`).
//  * Stateful getters: any callable `getter(std::uint32_t i)` returning a `glm::vec3` (a vertex
//    position) or a `cullkit::Aabb` (object bounds). A getter may hold references into your own
//    buffers, e.g. an interleaved vertex buffer with a stride (`StridedPositions` below).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <type_traits>
#include <utility>

#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include "config.hpp"
#include "geometry/aabb.hpp"

namespace cullkit {

/// Position of a vertex. Primary template deliberately empty: specialize it for your vertex type.
template <class Vertex, class Enable = void>
struct VertexTraits {};

template <>
struct VertexTraits<glm::vec3> {
  static glm::vec3 position(const glm::vec3& v) noexcept { return v; }
};
template <>
struct VertexTraits<glm::vec4> {
  static glm::vec3 position(const glm::vec4& v) noexcept { return glm::vec3(v); }
};
template <>
struct VertexTraits<std::array<float, 3>> {
  static glm::vec3 position(const std::array<float, 3>& v) noexcept { return glm::vec3(v[0], v[1], v[2]); }
};

/// Bounds of an object. Primary template deliberately empty: specialize it for your object type.
template <class Object, class Enable = void>
struct BoundsTraits {};

template <>
struct BoundsTraits<Aabb> {
  static Aabb bounds(const Aabb& b) noexcept { return b; }
};

namespace detail {
template <class Traits, class Vertex, class = void>
struct has_position : std::false_type {};
template <class Traits, class Vertex>
struct has_position<Traits, Vertex,
                    std::void_t<decltype(Traits::position(std::declval<const Vertex&>()))>>
    : std::is_convertible<decltype(Traits::position(std::declval<const Vertex&>())), glm::vec3> {};

template <class Traits, class Object, class = void>
struct has_bounds : std::false_type {};
template <class Traits, class Object>
struct has_bounds<Traits, Object, std::void_t<decltype(Traits::bounds(std::declval<const Object&>()))>>
    : std::is_convertible<decltype(Traits::bounds(std::declval<const Object&>())), Aabb> {};

template <class Getter, class Result, class = void>
struct is_getter : std::false_type {};
template <class Getter, class Result>
struct is_getter<Getter, Result, std::void_t<decltype(std::declval<const Getter&>()(std::uint32_t{}))>>
    : std::is_convertible<decltype(std::declval<const Getter&>()(std::uint32_t{})), Result> {};
}  // namespace detail

/// True when `Traits::position(const Vertex&)` exists and returns something convertible to glm::vec3.
template <class Vertex, class Traits = VertexTraits<Vertex>>
inline constexpr bool has_vertex_traits_v = detail::has_position<Traits, Vertex>::value;
/// True when `Traits::bounds(const Object&)` exists and returns something convertible to Aabb.
template <class Object, class Traits = BoundsTraits<Object>>
inline constexpr bool has_bounds_traits_v = detail::has_bounds<Traits, Object>::value;
/// True when `getter(std::uint32_t)` returns something convertible to glm::vec3.
template <class Getter>
inline constexpr bool is_position_getter_v = detail::is_getter<Getter, glm::vec3>::value;
/// True when `getter(std::uint32_t)` returns something convertible to Aabb.
template <class Getter>
inline constexpr bool is_bounds_getter_v = detail::is_getter<Getter, Aabb>::value;

/// Instantiating this checks the vertex requirement; the compiler's note names `Vertex`.
template <class Vertex, class Traits = VertexTraits<Vertex>>
struct require_vertex_traits {
  static_assert(has_vertex_traits_v<Vertex, Traits>,
                "cullkit: no vertex position for this Vertex type. Specialize "
                "cullkit::VertexTraits<Vertex> with `static glm::vec3 position(const Vertex&)`, "
                "or pass a Traits class that has it.");
  static constexpr bool value = true;
};
/// Instantiating this checks the bounds requirement; the compiler's note names `Object`.
template <class Object, class Traits = BoundsTraits<Object>>
struct require_bounds_traits {
  static_assert(has_bounds_traits_v<Object, Traits>,
                "cullkit: no bounds for this Object type. Specialize "
                "cullkit::BoundsTraits<Object> with `static cullkit::Aabb bounds(const Object&)`, "
                "or pass a Traits class that has it.");
  static constexpr bool value = true;
};

#if CULLKIT_HAS_CONCEPTS
/// C++20 spelling of `has_vertex_traits_v`.
template <class Vertex, class Traits = VertexTraits<Vertex>>
concept VertexWithTraits = has_vertex_traits_v<Vertex, Traits>;
/// C++20 spelling of `has_bounds_traits_v`.
template <class Object, class Traits = BoundsTraits<Object>>
concept ObjectWithBounds = has_bounds_traits_v<Object, Traits>;
template <class Getter>
concept PositionGetter = is_position_getter_v<Getter>;
template <class Getter>
concept BoundsGetter = is_bounds_getter_v<Getter>;
#endif

/// An indexed triangle list the caller owns: triangle t has corners
/// `vertices[indices[3t]]`, `vertices[indices[3t+1]]`, `vertices[indices[3t+2]]`, counter-clockwise
/// as seen from its front. `index_count` should be a multiple of 3; a trailing partial triangle is
/// ignored. Indices >= `vertex_count` make their triangle invalid (skipped and counted, never read).
template <class Vertex, class Index = std::uint32_t>
struct MeshView {
  const Vertex* vertices;
  std::size_t vertex_count;
  const Index* indices;
  std::size_t index_count;

  [[nodiscard]] std::size_t triangle_count() const noexcept { return index_count / 3; }
};

/// Reads triangle `t` of `mesh` into `out`; false (and `out` untouched) if an index is out of range.
template <class Traits, class Vertex, class Index>
[[nodiscard]] bool triangle_positions(const MeshView<Vertex, Index>& mesh, std::size_t t,
                                      glm::vec3 out[3]) noexcept {
  static_assert(require_vertex_traits<Vertex, Traits>::value, "");
  if constexpr (!has_vertex_traits_v<Vertex, Traits>) {
    return false;  // unreachable: the static_assert above already stopped the build
  } else {
  CULLKIT_ASSERT(t < mesh.triangle_count(), "triangle index within the mesh");
  std::size_t idx[3];
  for (int k = 0; k < 3; ++k) {
    const auto i = mesh.indices[3 * t + static_cast<std::size_t>(k)];
    if constexpr (std::is_signed_v<Index>) {
      if (i < 0) return false;
    }
    idx[k] = static_cast<std::size_t>(i);
    if (idx[k] >= mesh.vertex_count) return false;
  }
  for (int k = 0; k < 3; ++k) out[k] = glm::vec3(Traits::position(mesh.vertices[idx[k]]));
  return true;
  }
}
template <class Vertex, class Index>
[[nodiscard]] bool triangle_positions(const MeshView<Vertex, Index>& mesh, std::size_t t,
                                      glm::vec3 out[3]) noexcept {
  return triangle_positions<VertexTraits<Vertex>>(mesh, t, out);
}

/// A stateful position getter over an interleaved vertex buffer: vertex i's position is three
/// floats at `base + i * stride_bytes + offset_bytes`. Holds a pointer into your buffer.
struct StridedPositions {
  const unsigned char* base;
  std::size_t stride_bytes;
  std::size_t offset_bytes = 0;

  [[nodiscard]] glm::vec3 operator()(std::uint32_t i) const noexcept {
    float p[3];  // memcpy: the buffer need not be float-aligned
    std::memcpy(p, base + static_cast<std::size_t>(i) * stride_bytes + offset_bytes, sizeof p);
    return glm::vec3(p[0], p[1], p[2]);
  }
};

}  // namespace cullkit
