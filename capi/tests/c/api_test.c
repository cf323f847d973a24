/*
 * The C API under bad input: each call returns an error of the right kind whose message names
 * the argument, and the process goes on; frees of NULL and double frees through the nulled
 * handle are harmless. `api_test --no-gpu` runs only the calls that need no Vulkan (for
 * valgrind). Ends with the line "N passed, M failed".
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include <vklens.h>

#include "expect.h"

#include "../../../examples/c/vk_host.h"

static const double K[9] = {400, 0, 399.5, 0, 400, 299.5, 0, 0, 1};

static void cameras(void) {
    vkl_camera c = NULL;
    double d[7] = {-0.05, 0.01, 0.03, -0.01, 0, 0, 0};
    expect_error("load(NULL)", vkl_camera_load(NULL, &c), VKL_ERROR_INPUT, "path");
    expect_error("load(missing)", vkl_camera_load("/no/such/camera.yml", &c), VKL_ERROR_IO, "/no/such/camera.yml");
    expect_error("load(out NULL)", vkl_camera_load("x.yml", NULL), VKL_ERROR_INPUT, "out");
    expect_error("7 coefficients", vkl_camera_from_opencv(800, 600, K, d, 7, &c), VKL_ERROR_INPUT, "dist_coeffs");
    {
        vkl_error seven = vkl_camera_from_opencv(800, 600, K, d, 7, &c);
        expect("7 coefficients: the argument is dist_coeffs",
               vkl_error_argument(seven) && strcmp(vkl_error_argument(seven), "dist_coeffs") == 0);
        vkl_error_free(&seven);
        vkl_error small = vkl_camera_from_opencv(0, 600, K, d, 4, &c);
        expect("width 0: the argument is width, height",
               vkl_error_argument(small) && strcmp(vkl_error_argument(small), "width, height") == 0);
        vkl_error_free(&small);
    }
    double nan_k[9] = {400, 0, 399.5, 0, NAN, 299.5, 0, 0, 1};
    expect_error("NaN in K", vkl_camera_from_opencv(800, 600, nan_k, d, 4, &c), VKL_ERROR_INPUT, "K");
    expect_error("K NULL", vkl_camera_from_opencv(800, 600, NULL, d, 4, &c), VKL_ERROR_INPUT, "K");
    expect_error("coefficients NULL", vkl_camera_from_opencv(800, 600, K, NULL, 4, &c), VKL_ERROR_INPUT,
                 "dist_coeffs");
    double nan_d[4] = {NAN, 0, 0, 0};
    expect_error("NaN coefficient", vkl_camera_from_opencv(800, 600, K, nan_d, 4, &c), VKL_ERROR_INPUT, "k1");
    double neg_k[9] = {-400, 0, 399.5, 0, 400, 299.5, 0, 0, 1};
    expect_error("negative fx", vkl_camera_from_opencv(800, 600, neg_k, d, 4, &c), VKL_ERROR_INPUT, "fx");
    expect_error("zero width", vkl_camera_from_opencv(0, 600, K, d, 4, &c), VKL_ERROR_INPUT, "width");
    expect("no camera made by the failures", c == NULL);

    expect_ok("from_opencv", vkl_camera_from_opencv(800, 600, K, d, 4, &c));
    uint32_t w = 0, h = 0;
    expect_ok("size", vkl_camera_size(c, &w, &h));
    expect("size is 800x600", w == 800 && h == 600);
    expect_error("size(NULL camera)", vkl_camera_size(NULL, &w, &h), VKL_ERROR_INPUT, "camera");
    expect_error("size(NULL width)", vkl_camera_size(c, NULL, &h), VKL_ERROR_INPUT, "width");
    double xy[4] = {0.0, 0.0, 0.1, -0.2}, uv[4], back[4];
    expect_ok("distort", vkl_camera_distort_points(c, xy, 2, uv));
    expect("principal point maps to itself", uv[0] == 399.5 && uv[1] == 299.5);
    expect_ok("undistort", vkl_camera_undistort_points(c, uv, 2, back));
    expect("round trip", fabs(back[2] - 0.1) < 1e-12 && fabs(back[3] + 0.2) < 1e-12);
    expect_ok("in place", vkl_camera_undistort_points(c, uv, 2, uv));
    expect("in place round trip", fabs(uv[2] - 0.1) < 1e-12);
    expect_error("distort(NULL xy)", vkl_camera_distort_points(c, NULL, 2, uv), VKL_ERROR_INPUT, "xy");
    expect_error("distort(NULL out)", vkl_camera_distort_points(c, xy, 2, NULL), VKL_ERROR_INPUT, "uv_out");
    expect_error("distort(NULL camera)", vkl_camera_distort_points(NULL, xy, 2, uv), VKL_ERROR_INPUT, "camera");
    expect_ok("zero points, NULL arrays", vkl_camera_distort_points(c, NULL, 0, NULL));

    /* A strong barrel folds over where r(1 + k1 r^2) stops growing: pixels beyond have no
     * preimage and come back as NaN. */
    vkl_camera pin = NULL;
    double strong[4] = {-0.5, 0, 0, 0};
    expect_ok("strong barrel", vkl_camera_from_opencv(800, 600, K, strong, 4, &pin));
    double far[2] = {5000.0, 5000.0}, out[2];
    expect_ok("undistort outside the domain", vkl_camera_undistort_points(pin, far, 1, out));
    expect("NaN pair outside the valid domain", isnan(out[0]) && isnan(out[1]));
    vkl_camera_free(&pin);

    /* Every model of the table through the same calls: a double sphere seeing past 90°. */
    expect("model of the standard camera", strcmp(vkl_camera_model(c), "opencv") == 0);
    /* The model list: every name distinct, "opencv" first, NULL past the last. */
    size_t models = 0;
    while (vkl_model_name(models)) {
        for (size_t j = 0; j < models; ++j)
            expect("model names are distinct", strcmp(vkl_model_name(j), vkl_model_name(models)) != 0);
        models++;
    }
    expect("opencv is model 0", models > 0 && strcmp(vkl_model_name(0), "opencv") == 0);
    int listed = 0;
    for (size_t j = 0; j < models; ++j) listed |= strcmp(vkl_model_name(j), "double_sphere") == 0;
    expect("the double sphere is listed", listed);
    expect("model of NULL", vkl_camera_model(NULL) == NULL);
    const char *ds_path = "vkl_api_test_ds.json";
    FILE *f = fopen(ds_path, "w");
    expect("temporary camera file", f != NULL);
    if (f) {
        fputs("{\"model\": \"double_sphere\", \"width\": 752, \"height\": 480, \"fx\": 349.7, "
              "\"fy\": 348.9, \"cx\": 365.8, \"cy\": 249.9, \"xi\": -0.2, \"alpha\": 0.57}", f);
        fclose(f);
        vkl_camera ds = NULL;
        expect_ok("load a double sphere", vkl_camera_load(ds_path, &ds));
        remove(ds_path);
        expect("its model", ds && strcmp(vkl_camera_model(ds), "double_sphere") == 0);
        double xyz[6] = {1.0, 0.5, -0.2, 0.0, 0.0, -1.0}, px[4], rays[6];
        expect_ok("project", vkl_camera_project_points(ds, xyz, 2, px));
        expect("past 90 degrees seen, straight behind not", !isnan(px[0]) && isnan(px[2]));
        expect_ok("unproject", vkl_camera_unproject_points(ds, px, 1, rays));
        double norm = sqrt(1.0 + 0.25 + 0.04);
        expect("the ray back", fabs(rays[0] - 1.0 / norm) < 1e-12 && fabs(rays[2] + 0.2 / norm) < 1e-12);
        expect_error("project(NULL out)", vkl_camera_project_points(ds, xyz, 2, NULL), VKL_ERROR_INPUT, "uv_out");
        vkl_camera_free(&ds);
    }

    /* A camera of a file that holds several, by name and by index; a size for a file without. */
    const char *chain_path = "vkl_api_test_chain.yaml";
    f = fopen(chain_path, "w");
    expect("temporary camchain", f != NULL);
    if (f) {
        fputs("cam0:\n  camera_model: pinhole\n  intrinsics: [460, 459, 366, 249]\n"
              "  distortion_model: radtan\n  distortion_coeffs: [-0.27, 0.06, 0.0001, 0.00002]\n"
              "  resolution: [752, 480]\n"
              "cam1:\n  camera_model: ds\n  intrinsics: [-0.2, 0.57, 349.7, 348.9, 365.8, 249.9]\n"
              "  distortion_model: none\n  resolution: [752, 480]\n", f);
        fclose(f);
        vkl_load_options o = {VKL_API_VERSION, -1, "cam1", 0, 0};
        vkl_camera c1 = NULL;
        expect_ok("load_ex by name", vkl_camera_load_ex(chain_path, &o, &c1));
        expect("cam1 is the double sphere", c1 && strcmp(vkl_camera_model(c1), "double_sphere") == 0);
        vkl_camera_free(&c1);
        o.camera_name = NULL;
        o.camera_index = 0;
        expect_ok("load_ex by index", vkl_camera_load_ex(chain_path, &o, &c1));
        expect("cam0 is the standard model", c1 && strcmp(vkl_camera_model(c1), "opencv") == 0);
        vkl_camera_free(&c1);
        expect_ok("load_ex without options", vkl_camera_load_ex(chain_path, NULL, &c1));
        vkl_camera_free(&c1);
        o.camera_name = "cam7";
        vkl_error named = vkl_camera_load_ex(chain_path, &o, &c1);
        expect("unknown name: an input error naming its argument",
               vkl_error_kind_of(named) == VKL_ERROR_INPUT && vkl_error_argument(named)
               && strcmp(vkl_error_argument(named), "camera_name") == 0
               && strstr(vkl_error_message(named), "options.camera_name") != NULL
               && strstr(vkl_error_message(named), "cam7") != NULL);
        vkl_error_free(&named);
        expect("no argument of NULL", vkl_error_argument(NULL) == NULL);
        o.camera_name = NULL;
        o.camera_index = 0;
        o.width = 640;
        o.height = 480;
        expect_error("a size that disagrees", vkl_camera_load_ex(chain_path, &o, &c1), VKL_ERROR_INPUT, "752");
        o.width = 0;
        expect_error("half a size", vkl_camera_load_ex(chain_path, &o, &c1), VKL_ERROR_INPUT, "options.width");
        o.version = 99;
        expect_error("wrong version", vkl_camera_load_ex(chain_path, &o, &c1), VKL_ERROR_INPUT, "version");
        remove(chain_path);
    }

    /* Frees: NULL, and twice through the nulled handle. */
    vkl_camera_free(&c);
    expect("free nulls the handle", c == NULL);
    vkl_camera_free(&c);
    vkl_camera_free(NULL);
    vkl_error_free(NULL);
    vkl_error none = NULL;
    vkl_error_free(&none);
    expect("kind of NULL", vkl_error_kind_of(NULL) == VKL_ERROR_NONE);
    expect("message of NULL", strcmp(vkl_error_message(NULL), "") == 0);
    vkl_gpu_free(NULL);
    vkl_warper_free(NULL);
}

/* Scenes load, plan, explain and fail without a device: valgrind sees their frees too. The
 * camera path is relative to this file, which `base_path` stands for. */
static void scenes(void) {
    const char *text = "[geometry]\nscene = \"checkerboard:12x8:0.1\"\n"
                       "[optics]\ncamera = \"../../../examples/cameras/barrel_k1k2.json\"\n"
                       "[outputs]\ncolor = true\n"
                       "[sensor]\nrolling_shutter = \"top_to_bottom\"\n"
                       "[[poses]]\nrvec = [0.0, -0.08, 0.0]\ntvec = [-0.6521, -0.35, 1.2519]\n"
                       "end_rvec = [0.0, 0.08, 0.0]\nend_tvec = [-0.4444, -0.35, 1.3398]\n";
    vkl_scene s = NULL;
    expect_ok("scene_parse", vkl_scene_parse(text, __FILE__, &s));
    size_t count = 0;
    expect_ok("scene_frame_count", vkl_scene_frame_count(s, &count));
    expect("one frame", count == 1);
    char *plan = NULL;
    expect_ok("scene_explain", vkl_scene_explain(s, &plan));
    expect("the plan names the rolling shutter", plan && strstr(plan, "rolling") != NULL);
    vkl_string_free(&plan);
    expect("vkl_string_free nulls the string", plan == NULL);
    vkl_string_free(&plan);
    vkl_string_free(NULL);
    vkl_scene_free(&s);
    expect("vkl_scene_free nulls the handle", s == NULL);
    vkl_scene_free(&s);
    vkl_scene_free(NULL);
    expect_error("scene_load(missing)", vkl_scene_load("/no/such/scene.toml", &s), VKL_ERROR_IO,
                 "/no/such/scene.toml");
    expect_error("scene_parse(NULL text)", vkl_scene_parse(NULL, __FILE__, &s), VKL_ERROR_INPUT, "toml_text");
    expect_error("scene_parse(bad TOML)", vkl_scene_parse("[sensor", __FILE__, &s), VKL_ERROR_INPUT, "TOML");
    expect_error("scene_render(NULL device)", vkl_scene_render(NULL, NULL, 0, NULL), VKL_ERROR_INPUT, "out");
    expect("no scene made by the failures", s == NULL);
    vkl_frame_free(NULL);
    vkl_device_free(NULL);
}

static void gpu_and_warper(void) {
    host h;
    host_init(&h);
    vkl_gpu g = NULL;
    vkl_vulkan vk = {VKL_API_VERSION, h.instance, h.physical, h.device, h.queue, h.family, vkGetInstanceProcAddr};
    expect_error("gpu_create(NULL)", vkl_gpu_create(NULL, &g), VKL_ERROR_INPUT, "vk");
    vkl_vulkan wrong = vk;
    wrong.version = 99;
    expect_error("wrong version", vkl_gpu_create(&wrong, &g), VKL_ERROR_INPUT, "version");
    wrong = vk;
    wrong.get_instance_proc_addr = NULL;
    expect_error("NULL vkGetInstanceProcAddr", vkl_gpu_create(&wrong, &g), VKL_ERROR_INPUT, "get_instance_proc_addr");
    wrong = vk;
    wrong.device = VK_NULL_HANDLE;
    expect_error("NULL device", vkl_gpu_create(&wrong, &g), VKL_ERROR_INPUT, "device");
    wrong = vk;
    wrong.queue_family_index = 1000;
    expect_error("no such queue family", vkl_gpu_create(&wrong, &g), VKL_ERROR_INPUT, "queue family");
    expect_ok("gpu_create", vkl_gpu_create(&vk, &g));

    vkl_camera c = NULL;
    double d[4] = {-0.05, 0.01, 0.03, -0.01};
    expect_ok("camera", vkl_camera_from_opencv(800, 600, K, d, 4, &c));
    vkl_warper w = NULL;
    vkl_warp_options o = {VKL_API_VERSION, VKL_DISTORT, NULL, NULL, NULL, VK_FORMAT_R8G8B8A8_UNORM, {0, 0, 0, 0}, 0, NULL, NULL, NULL};
    vkl_warp_options bad = o;
    bad.direction = (vkl_direction)7;
    expect_error("direction 7", vkl_warper_create(g, c, &bad, &w), VKL_ERROR_INPUT, "direction");
    bad = o;
    bad.method = "bisection";
    expect_error("unknown method", vkl_warper_create(g, c, &bad, &w), VKL_ERROR_INPUT, "method");
    bad = o;
    bad.format = VK_FORMAT_B8G8R8A8_SRGB;
    expect_error("unsupported format", vkl_warper_create(g, c, &bad, &w), VKL_ERROR_INPUT, "format");
    bad = o;
    bad.frames_in_flight = 9;
    expect_error("nine frames in flight", vkl_warper_create(g, c, &bad, &w), VKL_ERROR_INPUT, "frames_in_flight");
    double mirror[9] = {1, 0, 0, 0, 1, 0, 0, 0, -1};
    double turn[9] = {0.9950041652780258, 0, 0.09983341664682815, 0, 1, 0, -0.09983341664682815, 0, 0.9950041652780258};
    bad = o;
    bad.rectification = turn;
    expect_error("a rectification on distort", vkl_warper_create(g, c, &bad, &w), VKL_ERROR_INPUT, "rectification");
    bad.direction = VKL_UNDISTORT;
    bad.rectification = mirror;
    expect_error("a mirror for a rotation", vkl_warper_create(g, c, &bad, &w), VKL_ERROR_INPUT, "rectification");
    bad.rectification = turn;
    expect_ok("a rectified undistort", vkl_warper_create(g, c, &bad, &w));
    vkl_warper_free(&w);
    bad = o;
    bad.interpolation = "lanczos";
    expect_error("unknown interpolation", vkl_warper_create(g, c, &bad, &w), VKL_ERROR_INPUT, "interpolation");
    bad = o;
    bad.border = "wrap";
    expect_error("unknown border", vkl_warper_create(g, c, &bad, &w), VKL_ERROR_INPUT, "border");
    bad.border = "reflect";
    bad.interpolation = "bicubic";
    expect_ok("a bicubic warp with a mirrored border", vkl_warper_create(g, c, &bad, &w));
    vkl_warper_free(&w);
    bad = o;
    bad.version = 0;
    expect_error("options version", vkl_warper_create(g, c, &bad, &w), VKL_ERROR_INPUT, "version");
    double chromatic[3] = {1.0, NAN, 1.0};
    bad = o;
    bad.chromatic = chromatic;
    expect_error("NaN chromatic", vkl_warper_create(g, c, &bad, &w), VKL_ERROR_INPUT, "chromatic");
    bad = o;
    bad.source_camera = c; /* distorted: not a pinhole */
    expect_error("distorted source camera", vkl_warper_create(g, c, &bad, &w), VKL_ERROR_INPUT, "source camera");
    expect_error("NULL gpu", vkl_warper_create(NULL, c, &o, &w), VKL_ERROR_INPUT, "gpu");
    expect("no warper made by the failures", w == NULL);
    expect_ok("warper_create with NULL options", vkl_warper_create(g, c, NULL, &w));
    vkl_warper_free(&w);
    expect_ok("warper_create", vkl_warper_create(g, c, &o, &w));

    /* A source of the wrong size: an error, and nothing recorded (the command buffer submits
     * empty under the validation layer). */
    VkImageUsageFlags usage = VK_IMAGE_USAGE_STORAGE_BIT;
    host_image small = host_image_create(&h, 64, 48, VK_FORMAT_R8G8B8A8_UNORM, usage);
    host_image out = host_image_create(&h, 800, 600, VK_FORMAT_R8G8B8A8_UNORM, usage);
    vkl_image small_ref = {small.image, small.view, small.width, small.height};
    vkl_image out_ref = {out.image, out.view, out.width, out.height};
    host_begin(&h);
    expect_error("source of the wrong size", vkl_warper_record(w, h.cmd, &small_ref, &out_ref, NULL), VKL_ERROR_INPUT,
                 "source");
    expect_error("output of the wrong size", vkl_warper_record(w, h.cmd, &out_ref, &small_ref, NULL), VKL_ERROR_INPUT,
                 "output");
    expect_error("NULL source", vkl_warper_record(w, h.cmd, NULL, &out_ref, NULL), VKL_ERROR_INPUT, "source");
    expect_error("NULL command buffer", vkl_warper_record(w, VK_NULL_HANDLE, &out_ref, &out_ref, NULL),
                 VKL_ERROR_INPUT, "cmd");
    expect_error("record_prepare(NULL)", vkl_warper_record_prepare(NULL, h.cmd), VKL_ERROR_INPUT, "warper");
    host_submit_and_wait(&h);
    uint32_t sw = 0, sh = 0;
    expect_error("source_size(NULL)", vkl_warper_source_size(NULL, &sw, &sh), VKL_ERROR_INPUT, "warper");
    expect_ok("source_size", vkl_warper_source_size(w, &sw, &sh));
    expect("source size", sw == 800 && sh == 600);

    vkl_warper_free(&w);
    vkl_warper_free(&w);
    vkl_gpu_free(&g);
    vkl_gpu_free(&g);
    vkl_camera_free(&c);
    host_image_destroy(&h, &small);
    host_image_destroy(&h, &out);
    int messages = h.validation_messages;
    host_destroy(&h);
    expect("no validation message", messages == 0);
}

int main(int argc, char **argv) {
    cameras();
    scenes();
    if (!(argc > 1 && strcmp(argv[1], "--no-gpu") == 0)) gpu_and_warper();
    printf("%d passed, %d failed\n", passed, failed);
    return failed != 0;
}
