// Uses only the installed public API: loads a model.yaml and prints, with 17
// significant digits, an EDM point, a camera ray, a pixel and the EDM point's
// sigma. Usage: consumer MODEL.yaml PHI THETA D X Y Z
#include <libcalib/api/rtscalib.h>

#include <cstdio>
#include <cstdlib>
#include <exception>

int main(int argc, char** argv) {
  if (argc != 8) {
    std::fprintf(stderr, "usage: consumer MODEL.yaml PHI THETA D X Y Z\n");
    return 2;
  }
  try {
    const rtscalib::CalibratedInstrument inst = rtscalib::CalibratedInstrument::Load(argv[1]);
    const double phi = std::atof(argv[2]), theta = std::atof(argv[3]), d = std::atof(argv[4]);
    const Eigen::Vector3d x(std::atof(argv[5]), std::atof(argv[6]), std::atof(argv[7]));
    const rtscalib::Uncertain<3> edm = inst.EdmPointWithUncertainty(phi, theta, d);
    std::printf("edm %.17g %.17g %.17g\n", edm.value[0], edm.value[1], edm.value[2]);
    const Eigen::Vector3d s = edm.Sigma();
    std::printf("edm_sigma %.17g %.17g %.17g\n", s[0], s[1], s[2]);
    const rtscalib::Ray ray =
        inst.CameraRay(0, phi, theta, inst.ImageWidth(0) / 2.0, inst.ImageHeight(0) / 2.0);
    std::printf("ray %.17g %.17g %.17g %.17g %.17g %.17g\n", ray.origin[0], ray.origin[1],
                ray.origin[2], ray.direction[0], ray.direction[1], ray.direction[2]);
    const Eigen::Vector2d uv = inst.Pixel(0, phi, theta, x);
    std::printf("pixel %.17g %.17g\n", uv[0], uv[1]);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "consumer: %s\n", e.what());
    return 1;
  }
  return 0;
}
