// cullkit/detail/box_proxy/table.hpp: the 27-entry outline table behind BoxProxy (entry 13, the
// inside of the box, is empty). Generated once offline from the brute-force rule (silhouette edges
// are the edges of the front faces not shared by two front faces, chained into a loop and turned
// counter-clockwise as seen from the eye) and re-derived by tests/box_proxy/test_box_proxy.cpp.
#pragma once

#include <cstdint>

namespace cullkit::detail {

/// One region of the eye against a box. Region index r = ix + 3*iy + 9*iz, each i in {0: below min,
/// 1: within [min, max], 2: above max}. Corner ids as `cullkit::corner` (bit 0 x, bit 1 y, bit 2 z,
/// set = max). Face id = 2 * axis + side (side 0: the min face, seen from below; 1: the max face).
struct BoxOutlineEntry {
  std::uint8_t corner_count;  ///< 0 (inside), 4 (one front face) or 6 (two or three)
  std::uint8_t face_count;    ///< front faces, 0..3, in ascending axis order
  std::uint8_t corners[6];    ///< outline corner ids, counter-clockwise seen from the eye
  std::uint8_t faces[3];      ///< front face ids
};

// Row comments: per axis "-" below min, "=" within [min, max], "+" above max.
// clang-format off
inline constexpr BoxOutlineEntry box_outline_table[27] = {
    {6, 3, {1, 5, 4, 6, 2, 3}, {0, 2, 4}},  //  0: x- y- z-
    {6, 2, {0, 2, 3, 1, 5, 4}, {2, 4, 0}},  //  1: x= y- z-
    {6, 3, {0, 2, 3, 7, 5, 4}, {1, 2, 4}},  //  2: x+ y- z-
    {6, 2, {0, 4, 6, 2, 3, 1}, {0, 4, 0}},  //  3: x- y= z-
    {4, 1, {0, 2, 3, 1, 0, 0}, {4, 0, 0}},  //  4: x= y= z-
    {6, 2, {0, 2, 3, 7, 5, 1}, {1, 4, 0}},  //  5: x+ y= z-
    {6, 3, {0, 4, 6, 7, 3, 1}, {0, 3, 4}},  //  6: x- y+ z-
    {6, 2, {0, 2, 6, 7, 3, 1}, {3, 4, 0}},  //  7: x= y+ z-
    {6, 3, {0, 2, 6, 7, 5, 1}, {1, 3, 4}},  //  8: x+ y+ z-
    {6, 2, {0, 1, 5, 4, 6, 2}, {0, 2, 0}},  //  9: x- y- z=
    {4, 1, {0, 1, 5, 4, 0, 0}, {2, 0, 0}},  // 10: x= y- z=
    {6, 2, {0, 1, 3, 7, 5, 4}, {1, 2, 0}},  // 11: x+ y- z=
    {4, 1, {0, 4, 6, 2, 0, 0}, {0, 0, 0}},  // 12: x- y= z=
    {0, 0, {0, 0, 0, 0, 0, 0}, {0, 0, 0}},  // 13: x= y= z=
    {4, 1, {1, 3, 7, 5, 0, 0}, {1, 0, 0}},  // 14: x+ y= z=
    {6, 2, {0, 4, 6, 7, 3, 2}, {0, 3, 0}},  // 15: x- y+ z=
    {4, 1, {2, 6, 7, 3, 0, 0}, {3, 0, 0}},  // 16: x= y+ z=
    {6, 2, {1, 3, 2, 6, 7, 5}, {1, 3, 0}},  // 17: x+ y+ z=
    {6, 3, {0, 1, 5, 7, 6, 2}, {0, 2, 5}},  // 18: x- y- z+
    {6, 2, {0, 1, 5, 7, 6, 4}, {2, 5, 0}},  // 19: x= y- z+
    {6, 3, {0, 1, 3, 7, 6, 4}, {1, 2, 5}},  // 20: x+ y- z+
    {6, 2, {0, 4, 5, 7, 6, 2}, {0, 5, 0}},  // 21: x- y= z+
    {4, 1, {4, 5, 7, 6, 0, 0}, {5, 0, 0}},  // 22: x= y= z+
    {6, 2, {1, 3, 7, 6, 4, 5}, {1, 5, 0}},  // 23: x+ y= z+
    {6, 3, {0, 4, 5, 7, 3, 2}, {0, 3, 5}},  // 24: x- y+ z+
    {6, 2, {2, 6, 4, 5, 7, 3}, {3, 5, 0}},  // 25: x= y+ z+
    {6, 3, {1, 3, 2, 6, 4, 5}, {1, 3, 5}},  // 26: x+ y+ z+
};
// clang-format on

}  // namespace cullkit::detail
