// cullkit/detail/nci/tolerances.hpp: the named margins of the NormalClassIndex's float and double
// arithmetic. Each one only ever makes a test keep more (a ray unfinished longer, a cell or a
// class kept, a triangle tested): changing one changes speed, never a pixel's answer.
#pragma once

namespace cullkit::detail::nci::tolerance {

// Relative error of a ray's direction component ratios (slopes) and of a ray parameter once
// rounded to float: a few float roundings (2^-24 each) with room to spare.
inline constexpr double float_slope = 1e-6;

}  // namespace cullkit::detail::nci::tolerance
