// bench/moc_peer.cpp: MocPeer over MOC's own API (compiled only when CULLKIT_MOC_DIR is set).
#include "moc_peer.hpp"

#include <cstddef>
#include <cstdlib>

using std::size_t;  // MOC's header uses size_t unqualified
#include <MaskedOcclusionCulling.h>

namespace cullkit_bench {

namespace {
MaskedOcclusionCulling* peer(void* p) { return static_cast<MaskedOcclusionCulling*>(p); }
}  // namespace

MocPeer::MocPeer(int width, int height, float near_w) {
  MaskedOcclusionCulling* m = MaskedOcclusionCulling::Create(MaskedOcclusionCulling::AVX2);
  m->SetResolution(static_cast<unsigned>(width), static_cast<unsigned>(height));
  m->SetNearClipPlane(near_w);
  m->ClearBuffer();
  moc_ = m;
}

MocPeer::~MocPeer() { MaskedOcclusionCulling::Destroy(peer(moc_)); }

const char* MocPeer::implementation() const {
  switch (peer(moc_)->GetImplementation()) {
    case MaskedOcclusionCulling::SSE2: return "SSE2";
    case MaskedOcclusionCulling::SSE41: return "SSE41";
    case MaskedOcclusionCulling::AVX2: return "AVX2";
    case MaskedOcclusionCulling::AVX512: return "AVX512";
  }
  return "?";
}

void MocPeer::clear() { peer(moc_)->ClearBuffer(); }

void MocPeer::render(const float* positions, int stride, const std::uint32_t* indices, int triangles,
                     const float* matrix) {
  peer(moc_)->RenderTriangles(positions, indices, triangles, matrix, MaskedOcclusionCulling::BACKFACE_CW,
                              MaskedOcclusionCulling::CLIP_PLANE_ALL,
                              MaskedOcclusionCulling::VertexLayout(stride, 4, 8));
}

bool MocPeer::rect_visible(float x0, float y0, float x1, float y1, float w_min) const {
  return peer(moc_)->TestRect(x0, y0, x1, y1, w_min) == MaskedOcclusionCulling::VISIBLE;
}

}  // namespace cullkit_bench
