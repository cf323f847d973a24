// A C++ program that only includes vklens.h and uses the camera functions: the header is
// valid C++ (its declarations sit in extern "C"), and the handles fit RAII.
//
//   c++ -std=c++17 examples/cpp/cameras.cpp $(pkg-config --cflags --libs vklens) -o cameras
//   ./cameras examples/cameras/prism_tilt.json
#include <vklens.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

// A vklens error as a C++ exception (the error handle is freed here).
void check(vkl_error e) {
    if (e != nullptr) {
        std::string message = vkl_error_message(e);
        vkl_error_free(&e);
        throw std::runtime_error(message);
    }
}

struct CameraDeleter {
    void operator()(vkl_camera_s* c) const { vkl_camera_free(&c); }
};
using Camera = std::unique_ptr<vkl_camera_s, CameraDeleter>;

Camera load(const char* path) {
    vkl_camera c = nullptr;
    check(vkl_camera_load(path, &c));
    return Camera(c);
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 2) {
        std::fprintf(stderr, "usage: %s CAMERA_FILE\n", argv[0]);
        return 2;
    }
    try {
        Camera camera = load(argv[1]);
        uint32_t width = 0, height = 0;
        check(vkl_camera_size(camera.get(), &width, &height));
        // A ray through each corner of the normalized square [-0.5, 0.5]^2, to pixels and back.
        std::vector<std::array<double, 2>> xy = {{-0.5, -0.5}, {0.5, -0.5}, {0.5, 0.5}, {-0.5, 0.5}};
        std::vector<std::array<double, 2>> uv(xy.size()), back(xy.size());
        check(vkl_camera_distort_points(camera.get(), xy[0].data(), xy.size(), uv[0].data()));
        check(vkl_camera_undistort_points(camera.get(), uv[0].data(), uv.size(), back[0].data()));
        double worst = 0;
        for (size_t i = 0; i < xy.size(); i++) {
            worst = std::fmax(worst, std::hypot(back[i][0] - xy[i][0], back[i][1] - xy[i][1]));
            std::printf("(%+.2f, %+.2f) -> (%.3f, %.3f) px\n", xy[i][0], xy[i][1], uv[i][0], uv[i][1]);
        }
        std::printf("%ux%u camera; round trip within %.1e\n", width, height, worst);
        // Bad input is an exception, not a crash.
        try {
            load("/no/such/camera.yml");
            return 1;
        } catch (const std::runtime_error& e) {
            std::printf("missing file: %s\n", e.what());
        }
        return worst < 1e-9 ? 0 : 1;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "%s\n", e.what());
        return 1;
    }
}
