// bench/moc_peer.hpp: a narrow door to Intel's Masked Occlusion Culling (MOC) for the races that
// compare against it. The peer is compiled from a folder named at configure time (CULLKIT_MOC_DIR),
// into its own library with its own flags; this header keeps its headers out of the benchmarks.
#pragma once

#include <cstdint>

namespace cullkit_bench {

/// One MOC depth buffer, AVX2 at most (as the acceptance race runs it), one thread.
class MocPeer {
 public:
  MocPeer(int width, int height, float near_w);
  ~MocPeer();
  MocPeer(const MocPeer&) = delete;
  MocPeer& operator=(const MocPeer&) = delete;

  /// The instruction set MOC picked ("SSE2", "SSE41", "AVX2", "AVX512").
  [[nodiscard]] const char* implementation() const;
  void clear();
  /// Rasterizes triangles of world positions (x, y, z floats, `stride` bytes apart) through the
  /// column-major 4x4 matrix, back faces of counter-clockwise-front geometry culled, clipped by
  /// every frustum plane.
  void render(const float* positions, int stride, const std::uint32_t* indices, int triangles, const float* matrix);
  /// True unless MOC says the normalized-device rectangle at clip depth `w_min` is occluded or off screen.
  [[nodiscard]] bool rect_visible(float x0, float y0, float x1, float y1, float w_min) const;

 private:
  void* moc_ = nullptr;
};

}  // namespace cullkit_bench
