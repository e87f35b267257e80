// cullkit inside OpenSceneGraph: a cull callback on the scene root asks cullkit which objects may be
// visible this frame, and a cull callback on every object skips the ones it leaves out.
//
// The scene is drawn into an offscreen buffer by OpenSceneGraph through whatever OpenGL the machine
// has (Mesa's llvmpipe under Xvfb on a server), once with cullkit and once without, from the same
// cameras. Every object is painted in a flat colour that encodes its index, with back faces culled
// (cullkit's rule: a triangle is seen from its front only) and a fixed near and far plane, so the two
// images must be identical pixel for pixel: an object cullkit left out was seen by no pixel. The
// program prints, per camera, the draws and the frame time (the fastest of three) with and without
// cullkit, and returns non-zero if any image differs.
//
// Usage: osg_cull_callback [output folder]   (writes osg_with_cullkit.png / osg_without_cullkit.png)
// The scene: the OpenArena map from the shared scenes folder when present, else a generated office.
#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include <osg/CullFace>
#include <osg/Geode>
#include <osg/Geometry>
#include <osg/Group>
#include <osg/Image>
#include <osg/Material>
#include <osg/NodeCallback>
#include <osg/ShadeModel>
#include <osgUtil/CullVisitor>
#include <osgViewer/Viewer>

#include <glm/gtc/type_ptr.hpp>

#include <cullkit/cullkit.hpp>
#include <cullkit_support/image.hpp>
#include <cullkit_support/scene.hpp>

namespace {

constexpr int kWidth = 480;
constexpr int kHeight = 270;

// One draw item of the application: its own vertex array and a 16-bit index buffer when its
// vertices fit (the engine's choice, not cullkit's: cullkit reads the whole scene's mesh).
osg::ref_ptr<osg::Geode> make_draw_item(const cullkit::support::Scene& scene, const cullkit::support::SceneObject& object,
                                        std::uint32_t object_index) {
  osg::ref_ptr<osg::Vec3Array> vertices = new osg::Vec3Array;
  std::vector<std::uint32_t> local;
  std::vector<std::uint32_t> remap(scene.positions.size(), ~0u);
  for (std::uint32_t t = object.first_triangle; t < object.first_triangle + object.triangle_count; ++t)
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t v = scene.indices[3 * t + k];
      if (remap[v] == ~0u) {
        remap[v] = static_cast<std::uint32_t>(vertices->size());
        const glm::vec3& p = scene.positions[v];
        vertices->push_back(osg::Vec3(p.x, p.y, p.z));
      }
      local.push_back(remap[v]);
    }
  osg::ref_ptr<osg::Geometry> geometry = new osg::Geometry;
  geometry->setVertexArray(vertices.get());
  if (vertices->size() <= 0xFFFFu) {
    osg::ref_ptr<osg::DrawElementsUShort> elements = new osg::DrawElementsUShort(GL_TRIANGLES);
    for (std::uint32_t i : local) elements->push_back(static_cast<GLushort>(i));
    geometry->addPrimitiveSet(elements.get());
  } else {
    osg::ref_ptr<osg::DrawElementsUInt> elements = new osg::DrawElementsUInt(GL_TRIANGLES);
    for (std::uint32_t i : local) elements->push_back(i);
    geometry->addPrimitiveSet(elements.get());
  }
  // The object's index, plus one (black is the background), as an exact 8-bit colour.
  const std::uint32_t id = object_index + 1;
  osg::ref_ptr<osg::Vec4Array> colour = new osg::Vec4Array;
  colour->push_back(osg::Vec4(static_cast<float>(id & 255u) / 255.0f, static_cast<float>((id >> 8) & 255u) / 255.0f,
                              static_cast<float>((id >> 16) & 255u) / 255.0f, 1.0f));
  geometry->setColorArray(colour.get(), osg::Array::BIND_OVERALL);
  geometry->setUseDisplayList(false);
  geometry->setUseVertexBufferObjects(true);
  osg::ref_ptr<osg::Geode> geode = new osg::Geode;
  geode->addDrawable(geometry.get());
  return geode;
}

// What cullkit decided this frame, shared by the root callback (which writes it) and the object
// callbacks (which read it).
struct FrameVisibility {
  bool enabled = true;
  std::vector<std::uint8_t> visible;    // by object index
  std::vector<std::uint32_t> list;      // cullkit's answer
  std::size_t draws = 0;                // objects the renderer went on to draw
  double cull_ms = 0.0;
};

class RootCullCallback : public osg::NodeCallback {
 public:
  RootCullCallback(const cullkit::MeshOcclusionCuller<glm::vec3>& culler, FrameVisibility& frame)
      : culler_(culler), frame_(frame) {}

  void operator()(osg::Node* node, osg::NodeVisitor* visitor) override {
    frame_.draws = 0;
    if (frame_.enabled) {
      auto* cull_visitor = visitor->asCullVisitor();
      const osg::Camera* camera = cull_visitor->getCurrentCamera();
      // OpenSceneGraph's matrices act on row vectors; their memory is the column-vector matrix that
      // cullkit (and GLM) expect, so the raw 16 numbers copy across unchanged.
      const osg::Matrixd view_proj = camera->getViewMatrix() * camera->getProjectionMatrix();
      glm::dmat4 m = glm::make_mat4(view_proj.ptr());
      const osg::Vec3d eye = osg::Matrixd::inverse(camera->getViewMatrix()).getTrans();
      cullkit::Camera view{glm::vec3(eye.x(), eye.y(), eye.z()), glm::mat4(m), kWidth, kHeight};
      const auto start = std::chrono::steady_clock::now();
      culler_.cull(view, context_, frame_.list);
      frame_.cull_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
      std::fill(frame_.visible.begin(), frame_.visible.end(), std::uint8_t{0});
      for (std::uint32_t i : frame_.list) frame_.visible[i] = 1;
    }
    traverse(node, visitor);
  }

 private:
  const cullkit::MeshOcclusionCuller<glm::vec3>& culler_;
  FrameVisibility& frame_;
  cullkit::MeshOcclusionContext context_;
};

class ObjectCullCallback : public osg::NodeCallback {
 public:
  ObjectCullCallback(std::uint32_t index, FrameVisibility& frame) : index_(index), frame_(frame) {}
  void operator()(osg::Node* node, osg::NodeVisitor* visitor) override {
    if (frame_.enabled && !frame_.visible[index_]) return;  // cullkit: nothing of it can be seen
    ++frame_.draws;
    traverse(node, visitor);
  }

 private:
  std::uint32_t index_;
  FrameVisibility& frame_;
};

// Copies the finished frame out of the GL buffer after each draw.
struct Capture : osg::Camera::DrawCallback {
  osg::ref_ptr<osg::Image> image = new osg::Image;
  void operator()(osg::RenderInfo&) const override {
    image->readPixels(0, 0, kWidth, kHeight, GL_RGB, GL_UNSIGNED_BYTE);
  }
};

struct Eye {
  osg::Vec3d position, target;
};

// Cameras from inside the scene: a ring of views around points spread over the scene box at eye
// height, so some look down corridors and some straight at walls.
std::vector<Eye> make_eyes(const cullkit::Aabb& bounds, bool y_is_height) {
  std::vector<Eye> eyes;
  const glm::vec3 size = bounds.max - bounds.min;
  for (int p = 0; p < 3; ++p) {
    const float f = 0.3f + 0.2f * static_cast<float>(p);
    glm::vec3 at = bounds.min + size * glm::vec3(f, 0.35f, 1.0f - f);
    if (!y_is_height) at.y = bounds.min.y + 1.7f;
    for (int k = 0; k < 4; ++k) {
      const double a = 6.283185307179586 * (k + 0.125 * p) / 4.0;
      const osg::Vec3d from(at.x, at.y, at.z);
      eyes.push_back({from, from + osg::Vec3d(std::cos(a), -0.1, std::sin(a))});
    }
  }
  return eyes;
}

}  // namespace

int main(int argc, char** argv) {
  namespace support = cullkit::support;
  const std::string out_dir = argc > 1 ? argv[1] : ".";

  support::Scene scene;
  bool real = false;
  if (!support::scenes_dir().empty()) {
    if (auto loaded = support::load_obj(support::scenes_dir() + "/oacmpdm9.obj")) {
      scene = std::move(*loaded);
      real = true;
    }
  }
  if (!real) scene = support::make_office(1, 10, 8);
  std::printf("scene: %s, %zu triangles, %zu objects\n", real ? "oacmpdm9 (OpenArena)" : "generated office",
              scene.triangle_count(), scene.objects.size());

  std::vector<cullkit::MeshObject> objects;
  for (const auto& o : scene.objects) objects.push_back({o.first_triangle, o.triangle_count});
  const cullkit::MeshOcclusionCuller<glm::vec3> culler(scene.mesh(), objects.data(), objects.size());

  FrameVisibility frame;
  frame.visible.assign(scene.objects.size(), 1);
  osg::ref_ptr<osg::Group> root = new osg::Group;
  for (std::uint32_t i = 0; i < scene.objects.size(); ++i) {
    osg::ref_ptr<osg::Geode> item = make_draw_item(scene, scene.objects[i], i);
    item->setCullCallback(new ObjectCullCallback(i, frame));
    // OpenSceneGraph's own small-feature and view-frustum culling stay on: cullkit comes on top.
    root->addChild(item.get());
  }
  root->setCullCallback(new RootCullCallback(culler, frame));
  osg::StateSet* state = root->getOrCreateStateSet();
  state->setMode(GL_LIGHTING, osg::StateAttribute::OFF);
  state->setMode(GL_DITHER, osg::StateAttribute::OFF);
  state->setMode(GL_BLEND, osg::StateAttribute::OFF);
  state->setAttributeAndModes(new osg::CullFace(osg::CullFace::BACK), osg::StateAttribute::ON);
  state->setAttributeAndModes(new osg::ShadeModel(osg::ShadeModel::FLAT), osg::StateAttribute::ON);

  osg::ref_ptr<osg::GraphicsContext::Traits> traits = new osg::GraphicsContext::Traits;
  traits->readDISPLAY();  // the X display from $DISPLAY (xvfb-run sets it)
  traits->setUndefinedScreenDetailsToDefaultScreen();
  traits->width = kWidth;
  traits->height = kHeight;
  traits->pbuffer = true;
  traits->doubleBuffer = false;
  traits->red = traits->green = traits->blue = 8;
  traits->depth = 24;
  traits->samples = 0;
  osg::ref_ptr<osg::GraphicsContext> gc = osg::GraphicsContext::createGraphicsContext(traits.get());
  if (!gc) {
    traits->pbuffer = false;  // some GLX servers offer no pbuffer: an unmapped window works as well
    gc = osg::GraphicsContext::createGraphicsContext(traits.get());
  }
  if (!gc) {
    std::printf("no OpenGL context (no X display?): nothing to compare\n");
    return 77;  // CTest's SKIP_RETURN_CODE
  }

  osgViewer::Viewer viewer;
  viewer.setThreadingModel(osgViewer::Viewer::SingleThreaded);
  viewer.setSceneData(root.get());
  osg::Camera* camera = viewer.getCamera();
  camera->setGraphicsContext(gc.get());
  camera->setViewport(0, 0, kWidth, kHeight);
  camera->setClearColor(osg::Vec4(0, 0, 0, 1));
  camera->setComputeNearFarMode(osg::CullSettings::DO_NOT_COMPUTE_NEAR_FAR);
  const double diagonal = static_cast<double>(glm::length(scene.bounds.max - scene.bounds.min));
  camera->setProjectionMatrixAsPerspective(60.0, static_cast<double>(kWidth) / kHeight, diagonal * 1e-4,
                                           diagonal * 2.0);
  const GLenum buffer = traits->doubleBuffer ? GL_BACK : GL_FRONT;
  camera->setDrawBuffer(buffer);
  camera->setReadBuffer(buffer);
  osg::ref_ptr<Capture> capture = new Capture;
  camera->setFinalDrawCallback(capture.get());
  viewer.realize();

  const std::vector<Eye> eyes = make_eyes(scene.bounds, real);
  std::size_t differing_frames = 0, draws_with = 0, draws_without = 0;
  double ms_with = 0.0, ms_without = 0.0, cull_ms = 0.0;
  std::vector<unsigned char> cullkit_pixels;
  for (std::size_t e = 0; e < eyes.size(); ++e) {
    camera->setViewMatrixAsLookAt(eyes[e].position, eyes[e].target, osg::Vec3d(0, 1, 0));
    std::size_t draws[2] = {0, 0};
    double ms[2] = {0.0, 0.0};
    for (int pass = 0; pass < 2; ++pass) {
      frame.enabled = pass == 0;
      viewer.frame();  // warm: buffers uploaded, caches filled
      ms[pass] = 1e30;  // the fastest of three frames: the least disturbed by other work on the machine
      for (int repeat = 0; repeat < 3; ++repeat) {
        const auto start = std::chrono::steady_clock::now();
        viewer.frame();
        ms[pass] = std::min(ms[pass], std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
      }
      draws[pass] = frame.draws;
      if (pass == 0) {
        cull_ms += frame.cull_ms;
        cullkit_pixels.assign(capture->image->data(), capture->image->data() + kWidth * kHeight * 3);
      }
    }
    // cullkit_pixels holds the frame drawn with cullkit; the capture now holds the plain one.
    std::size_t differing = 0;
    const unsigned char* plain = capture->image->data();
    for (int i = 0; i < kWidth * kHeight * 3; i += 3)
      differing += plain[i] != cullkit_pixels[i] || plain[i + 1] != cullkit_pixels[i + 1] ||
                   plain[i + 2] != cullkit_pixels[i + 2];
    if (differing) ++differing_frames;
    std::printf("camera %2zu: draws %5zu with cullkit, %5zu without; frame %.2f ms with, %.2f ms without; %zu pixels differ\n",
                e, draws[0], draws[1], ms[0], ms[1], differing);
    draws_with += draws[0];
    draws_without += draws[1];
    ms_with += ms[0];
    ms_without += ms[1];
    if (e == 0) {
      auto write = [&](const unsigned char* rgb, const char* name) {
        support::Image picture(kWidth, kHeight);
        for (int y = 0; y < kHeight; ++y)
          for (int x = 0; x < kWidth; ++x) {
            const unsigned char* p = rgb + 3 * ((kHeight - 1 - y) * kWidth + x);  // GL rows run upwards
            const std::uint32_t id = p[0] | (p[1] << 8) | (p[2] << 16);
            picture.set(x, y, id ? support::id_color(id) : support::Rgb{0, 0, 0});
          }
        picture.write_png(out_dir + "/" + name);
      };
      write(cullkit_pixels.data(), "osg_with_cullkit.png");
      write(plain, "osg_without_cullkit.png");
    }
  }
  const double n = static_cast<double>(eyes.size());
  std::printf("average: draws %.0f with cullkit, %.0f without (%.1f%%); frame %.2f ms with (cullkit %.3f ms of it), "
              "%.2f ms without\n",
              draws_with / n, draws_without / n, 100.0 * static_cast<double>(draws_with) / static_cast<double>(draws_without),
              ms_with / n, cull_ms / n, ms_without / n);
  std::printf("%zu of %zu frames differ\n", differing_frames, eyes.size());
  return differing_frames == 0 ? 0 : 1;
}
