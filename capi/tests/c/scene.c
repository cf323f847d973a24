/*
 * Scene rendering through the C API: the rolling-shutter example and its global-shutter twin
 * rendered and compared, a still rolling shutter against the global render bit for bit, and
 * the error paths (missing file, bad key, NULL arguments, frame index out of range).
 *
 *   scene REPO OUT
 *
 * REPO is the repository root (for examples/scenes/); the rolling-shutter frame's outputs are
 * written raw to OUT/color.bin, OUT/ids.bin and OUT/depth.bin, so that the test harness can
 * compare them with the Rust library's render. Ends with the line "N passed, M failed".
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <vklens.h>

#include "expect.h"

/* An output of a frame, copied out: NULL when the frame lacks it. */
static void *copy_output(vkl_frame f, vkl_output which, vkl_pixel_format *format, size_t *bytes) {
    *format = VKL_PIXELS_NONE;
    *bytes = 0;
    if (!expect_ok("vkl_frame_output", vkl_frame_output(f, which, format, bytes)) || *format == VKL_PIXELS_NONE)
        return NULL;
    void *data = malloc(*bytes);
    if (!data || !expect_ok("vkl_frame_copy", vkl_frame_copy(f, which, data, *bytes))) {
        free(data);
        return NULL;
    }
    return data;
}

static void write_file(const char *dir, const char *name, const void *data, size_t bytes) {
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    FILE *f = fopen(path, "wb");
    expect("open the output file", f != NULL);
    if (f) {
        expect("write the output file", fwrite(data, 1, bytes, f) == bytes);
        fclose(f);
    }
}

/* A scene's one frame: size and outputs. */
typedef struct {
    uint32_t width, height;
    uint8_t *color; /* RGBA8 */
    uint32_t *ids;
    float *depth;
    size_t color_bytes, ids_bytes, depth_bytes;
} rendered;

static void free_rendered(rendered *r) {
    free(r->color);
    free(r->ids);
    free(r->depth);
    memset(r, 0, sizeof *r);
}

/* Renders the one frame of `s` and checks that it has the outputs the example scenes ask for
 * (colour as RGBA8, IDs, depth, no flow), each of the frame's size. */
static int render_one(const char *what, vkl_device d, vkl_scene s, rendered *r) {
    memset(r, 0, sizeof *r);
    vkl_frame f = NULL;
    char label[256];
    snprintf(label, sizeof label, "%s: render", what);
    if (!expect_ok(label, vkl_scene_render(d, s, 0, &f))) return 0;
    expect_ok("frame size", vkl_frame_size(f, &r->width, &r->height));
    size_t index = 99;
    double ms = -1;
    expect_ok("frame info", vkl_frame_info(f, &index, &ms));
    expect("frame index 0 and a time", index == 0 && ms >= 0);
    expect_ok("frame info, neither wanted", vkl_frame_info(f, NULL, NULL));
    size_t pixels = (size_t)r->width * r->height;
    vkl_pixel_format fmt;
    r->color = copy_output(f, VKL_OUTPUT_COLOR, &fmt, &r->color_bytes);
    expect("colour is RGBA8 of the frame's size", r->color && fmt == VKL_PIXELS_RGBA8 && r->color_bytes == 4 * pixels);
    r->ids = copy_output(f, VKL_OUTPUT_IDS, &fmt, &r->ids_bytes);
    expect("ids are uint32 of the frame's size", r->ids && fmt == VKL_PIXELS_R32_UINT && r->ids_bytes == 4 * pixels);
    r->depth = copy_output(f, VKL_OUTPUT_DEPTH, &fmt, &r->depth_bytes);
    expect("depth is float of the frame's size", r->depth && fmt == VKL_PIXELS_R32F && r->depth_bytes == 4 * pixels);
    size_t flow_bytes = 1;
    expect_ok("flow output", vkl_frame_output(f, VKL_OUTPUT_FLOW, &fmt, &flow_bytes));
    expect("no flow (the scene does not ask for it)", fmt == VKL_PIXELS_NONE && flow_bytes == 0);

    /* The frame's own error paths. */
    uint8_t small[8];
    expect_error("copy flow the scene did not ask for", vkl_frame_copy(f, VKL_OUTPUT_FLOW, small, sizeof small),
                 VKL_ERROR_INPUT, "flow");
    expect_error("copy into too small a buffer", vkl_frame_copy(f, VKL_OUTPUT_COLOR, small, sizeof small),
                 VKL_ERROR_INPUT, "dst_bytes");
    expect_error("copy into NULL", vkl_frame_copy(f, VKL_OUTPUT_IDS, NULL, r->ids_bytes), VKL_ERROR_INPUT, "dst");
    expect_error("an output that does not exist", vkl_frame_output(f, 99, &fmt, NULL), VKL_ERROR_INPUT, "which");
    expect_error("size of a NULL frame", vkl_frame_size(NULL, &r->width, &r->height), VKL_ERROR_INPUT, "frame");
    expect_error("copy from a NULL frame", vkl_frame_copy(NULL, VKL_OUTPUT_COLOR, small, sizeof small),
                 VKL_ERROR_INPUT, "frame");
    vkl_frame_free(&f);
    expect("vkl_frame_free nulls the handle", f == NULL);
    vkl_frame_free(&f);
    return r->color && r->ids && r->depth;
}

static char *read_text(const char *path) {
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *text = malloc((size_t)n + 1);
    if (text && fread(text, 1, (size_t)n, f) != (size_t)n) {
        free(text);
        text = NULL;
    }
    if (text) text[n] = '\0';
    fclose(f);
    return text;
}

int main(int argc, char **argv) {
    if (argc != 3) {
        fprintf(stderr, "usage: scene REPO OUT\n");
        return 2;
    }
    const char *repo = argv[1], *out_dir = argv[2];
    char rolling_path[4096], global_path[4096], camera_path[4096];
    snprintf(rolling_path, sizeof rolling_path, "%s/examples/scenes/rolling_shutter.toml", repo);
    snprintf(global_path, sizeof global_path, "%s/examples/scenes/rolling_shutter_global.toml", repo);
    snprintf(camera_path, sizeof camera_path, "%s/examples/cameras/barrel_k1k2.json", repo);

    /* Loading and planning need no device. */
    vkl_scene rolling = NULL, global = NULL, scene = NULL;
    expect_ok("load rolling_shutter.toml", vkl_scene_load(rolling_path, &rolling));
    expect_ok("load rolling_shutter_global.toml", vkl_scene_load(global_path, &global));
    size_t count = 0;
    expect_ok("frame count", vkl_scene_frame_count(rolling, &count));
    expect("one pose", count == 1);
    double px = -1;
    expect_ok("expected error", vkl_scene_expected_error_px(rolling, &px));
    expect("expected error is a small number of pixels", px >= 0 && px < 1);
    char *plan = NULL;
    expect_ok("explain", vkl_scene_explain(rolling, &plan));
    expect("the plan is text", plan && strlen(plan) > 0);
    vkl_string_free(&plan);
    expect("vkl_string_free nulls the string", plan == NULL);
    vkl_string_free(&plan);
    vkl_string_free(NULL);

    /* Error paths of loading. */
    expect_error("missing file", vkl_scene_load("/no/such/scene.toml", &scene), VKL_ERROR_IO,
                 "/no/such/scene.toml");
    expect_error("load(NULL path)", vkl_scene_load(NULL, &scene), VKL_ERROR_INPUT, "path");
    expect_error("load(NULL out)", vkl_scene_load(rolling_path, NULL), VKL_ERROR_INPUT, "out");
    /* The example with one value, or one key, wrong: the message names the key. */
    char *rolling_text = read_text(rolling_path);
    expect("read rolling_shutter.toml", rolling_text != NULL);
    char *readout = rolling_text ? strstr(rolling_text, "\"top_to_bottom\"") : NULL;
    expect("the example reads top to bottom", readout != NULL);
    if (readout) {
        char bad[8192];
        *readout = '\0';
        snprintf(bad, sizeof bad, "%s\"diagonal\"%s", rolling_text, readout + strlen("\"top_to_bottom\""));
        expect_error2("an unknown readout", vkl_scene_parse(bad, rolling_path, &scene), VKL_ERROR_INPUT,
                      "rolling_shutter", "diagonal");
        snprintf(bad, sizeof bad, "%s\"top_to_bottom\"\nreadout_ms = 3%s", rolling_text,
                 readout + strlen("\"top_to_bottom\""));
        expect_error("an unknown key", vkl_scene_parse(bad, rolling_path, &scene), VKL_ERROR_INPUT, "readout_ms");
        *readout = '"';
    }
    free(rolling_text);
    expect_error("not TOML", vkl_scene_parse("[geometry", NULL, &scene), VKL_ERROR_INPUT, "TOML");
    expect_error("parse(NULL text)", vkl_scene_parse(NULL, NULL, &scene), VKL_ERROR_INPUT, "toml_text");
    expect_error("parse(NULL out)", vkl_scene_parse("", NULL, NULL), VKL_ERROR_INPUT, "out");
    expect_error("frame count of NULL", vkl_scene_frame_count(NULL, &count), VKL_ERROR_INPUT, "scene");
    expect_error("frame count into NULL", vkl_scene_frame_count(rolling, NULL), VKL_ERROR_INPUT, "count");
    expect_error("explain NULL", vkl_scene_explain(NULL, &plan), VKL_ERROR_INPUT, "scene");
    expect_error("expected error of NULL", vkl_scene_expected_error_px(NULL, &px), VKL_ERROR_INPUT, "scene");
    expect("no scene made by the failures", scene == NULL);

    vkl_device d = NULL;
    if (!expect_ok("device", vkl_device_create(&d))) goto done;
    expect("the device has a name", vkl_device_name(d) && strlen(vkl_device_name(d)) > 0);
    expect("NULL device has none", vkl_device_name(NULL) == NULL);
    expect_error("device(NULL out)", vkl_device_create(NULL), VKL_ERROR_INPUT, "out");

    vkl_frame f = NULL;
    expect_error("frame index out of range", vkl_scene_render(d, rolling, 1, &f), VKL_ERROR_INPUT, "frame_index");
    expect_error("render(NULL device)", vkl_scene_render(NULL, rolling, 0, &f), VKL_ERROR_INPUT, "device");
    expect_error("render(NULL scene)", vkl_scene_render(d, NULL, 0, &f), VKL_ERROR_INPUT, "scene");
    expect_error("render(NULL out)", vkl_scene_render(d, rolling, 0, NULL), VKL_ERROR_INPUT, "out");
    expect("no frame made by the failures", f == NULL);

    /* The two shutters: the same size as the camera, the board bent by the moving one. */
    rendered r = {0}, g = {0}, still = {0};
    if (render_one("rolling", d, rolling, &r) && render_one("global", d, global, &g)) {
        vkl_camera cam = NULL;
        uint32_t cw = 0, ch = 0;
        expect_ok("the scene's camera", vkl_camera_load(camera_path, &cam));
        expect_ok("its size", vkl_camera_size(cam, &cw, &ch));
        vkl_camera_free(&cam);
        expect("the frames are the camera's size", r.width == cw && r.height == ch && g.width == cw && g.height == ch);
        size_t pixels = (size_t)r.width * r.height, differ = 0, first_row = 0, drawn = 0;
        for (size_t i = 0; i < pixels; i++) {
            int same = memcmp(r.color + 4 * i, g.color + 4 * i, 4) == 0;
            differ += !same;
            if (i < r.width) first_row += !same;
            drawn += r.ids[i] != 0;
        }
        printf("rolling vs global: %zu of %zu pixels differ, %zu of the first row's %u; %zu drawn\n", differ, pixels,
               first_row, r.width, drawn);
        expect("the board is drawn", drawn > pixels / 4);
        /* Measured on lavapipe: 22% of the pixels differ (the board's edges lean). */
        expect("the moving shutter bends the board", differ > pixels / 10);
        /* The first line is read at the start pose, which both share. On lavapipe it agrees to
         * the last bit (0 of 800 pixels differ) although the routes differ (the vertex path
         * against the global one); 1% leaves room for a device that rounds an edge pixel
         * differently. */
        expect("the first row mostly agrees", first_row * 100 <= r.width);
        write_file(out_dir, "color.bin", r.color, r.color_bytes);
        write_file(out_dir, "ids.bin", r.ids, r.ids_bytes);
        write_file(out_dir, "depth.bin", r.depth, r.depth_bytes);

        /* A rolling shutter that does not move is the global shutter, bit for bit. */
        char *text = read_text(rolling_path);
        expect("read rolling_shutter.toml", text != NULL);
        char *end = text ? strstr(text, "end_rvec") : NULL;
        expect("the example has an end pose", end != NULL);
        if (end) {
            *end = '\0';
            char still_text[8192];
            snprintf(still_text, sizeof still_text,
                     "%send_rvec = [0.0, -0.08, 0.0]\nend_tvec = [-0.6521, -0.35, 1.2519]\n", text);
            expect_ok("parse the still rolling shutter", vkl_scene_parse(still_text, rolling_path, &scene));
            if (scene && render_one("still", d, scene, &still)) {
                expect("still: colour equals the global shutter's bit for bit",
                       still.color_bytes == g.color_bytes && memcmp(still.color, g.color, g.color_bytes) == 0);
                expect("still: ids equal the global shutter's bit for bit",
                       still.ids_bytes == g.ids_bytes && memcmp(still.ids, g.ids, g.ids_bytes) == 0);
                expect("still: depth equals the global shutter's bit for bit",
                       still.depth_bytes == g.depth_bytes && memcmp(still.depth, g.depth, g.depth_bytes) == 0);
            }
            vkl_scene_free(&scene);
        }
        free(text);

        /* Float colour (`[outputs] format = "exr"`) comes back as RGBA32F. */
        const char *hdr = "[geometry]\nscene = \"checkerboard:12x8:0.1\"\n"
                          "[optics]\ncamera = \"../cameras/barrel_k1k2.json\"\n"
                          "[outputs]\ncolor = true\nformat = \"exr\"\n"
                          "[[poses]]\nrvec = [0.0, -0.08, 0.0]\ntvec = [-0.6521, -0.35, 1.2519]\n";
        expect_ok("parse a float-colour scene", vkl_scene_parse(hdr, rolling_path, &scene));
        vkl_frame hf = NULL;
        if (scene && expect_ok("render float colour", vkl_scene_render(d, scene, 0, &hf))) {
            vkl_pixel_format fmt = VKL_PIXELS_NONE;
            size_t bytes = 0;
            expect_ok("float colour output", vkl_frame_output(hf, VKL_OUTPUT_COLOR, &fmt, &bytes));
            expect("float colour is RGBA32F, 16 bytes a pixel",
                   fmt == VKL_PIXELS_RGBA32F && bytes == 16 * (size_t)r.width * r.height);
            expect_ok("no ids asked for", vkl_frame_output(hf, VKL_OUTPUT_IDS, &fmt, &bytes));
            expect("no ids", fmt == VKL_PIXELS_NONE && bytes == 0);
        }
        vkl_frame_free(&hf);
        vkl_scene_free(&scene);

        /* Labels: examples/scenes/ground_truth.toml (a 200° fisheye over the named boxes). */
        char gt_path[4096];
        snprintf(gt_path, sizeof gt_path, "%s/examples/scenes/ground_truth.toml", repo);
        vkl_frame lf = NULL;
        if (expect_ok("load ground_truth.toml", vkl_scene_load(gt_path, &scene)) &&
            expect_ok("render the labels", vkl_scene_render(d, scene, 0, &lf))) {
            uint32_t w = 0, h = 0;
            expect_ok("labels: frame size", vkl_frame_size(lf, &w, &h));
            size_t pixels = (size_t)w * h, bytes = 0;
            vkl_pixel_format fmt;
            uint32_t *ids = copy_output(lf, VKL_OUTPUT_IDS, &fmt, &bytes);
            uint32_t *classes = copy_output(lf, VKL_OUTPUT_CLASSES, &fmt, &bytes);
            expect("classes are uint32 of the frame's size", classes && fmt == VKL_PIXELS_R32_UINT && bytes == 4 * pixels);
            float *range = copy_output(lf, VKL_OUTPUT_RANGE, &fmt, &bytes);
            float *depth = copy_output(lf, VKL_OUTPUT_DEPTH, &fmt, &bytes);
            expect("range is float of the frame's size", range && fmt == VKL_PIXELS_R32F && bytes == 4 * pixels);
            if (ids && classes && range && depth) {
                size_t bad = 0;
                for (size_t i = 0; i < pixels; i++) {
                    /* [classes]: box_red (ID 2) is 2, the other boxes 1, the floor 0. */
                    uint32_t want = ids[i] == 2 ? 2 : ids[i] >= 3 ? 1 : 0;
                    bad += classes[i] != want;
                    if (ids[i] != 0) bad += !(range[i] >= fabsf(depth[i]) * (1.0f - 1e-6f));
                    else bad += !isinf(range[i]);
                }
                expect("classes follow the IDs and range the rays", bad == 0);
            }
            free(ids);
            free(classes);
            free(range);
            free(depth);
            char *json = NULL;
            expect_ok("labels as JSON", vkl_frame_labels_json(lf, &json));
            expect("the JSON lists the objects, boxes and keypoints",
                   json && strstr(json, "\"box_red\"") && strstr(json, "\"bbox_full\"") &&
                       strstr(json, "\"under_green\""));
            vkl_string_free(&json);
            expect_error("labels of a NULL frame", vkl_frame_labels_json(NULL, &json), VKL_ERROR_INPUT, "frame");
            expect_error("labels into NULL", vkl_frame_labels_json(lf, NULL), VKL_ERROR_INPUT, "out");
        }
        vkl_frame_free(&lf);
        vkl_scene_free(&scene);
    }
    free_rendered(&r);
    free_rendered(&g);
    free_rendered(&still);
    expect_ok("no validation messages", vkl_device_check_validation(d));
    expect_error("validation of NULL", vkl_device_check_validation(NULL), VKL_ERROR_INPUT, "device");
    vkl_device_free(&d);
    expect("vkl_device_free nulls the handle", d == NULL);
    vkl_device_free(&d);

done:
    vkl_scene_free(&rolling);
    vkl_scene_free(&global);
    expect("vkl_scene_free nulls the handle", rolling == NULL);
    vkl_scene_free(&rolling);
    vkl_scene_free(NULL);
    printf("%d passed, %d failed\n", passed, failed);
    return failed == 0 ? 0 : 1;
}
