/*
 * points CAMERA_FILE distort|undistort: reads pairs of doubles (native binary) from stdin,
 * writes the C API's answers for them, the same way, to stdout. The Rust side compares them
 * bit for bit with the library's own.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <vklens.h>

int main(int argc, char **argv) {
    if (argc != 3) {
        fprintf(stderr, "usage: %s CAMERA_FILE distort|undistort\n", argv[0]);
        return 2;
    }
    size_t cap = 1 << 16, n = 0;
    double *in = malloc(cap * sizeof *in);
    size_t got;
    while (in && (got = fread(in + n, sizeof *in, cap - n, stdin)) > 0) {
        n += got;
        if (n == cap) {
            double *bigger = realloc(in, 2 * cap * sizeof *in);
            if (!bigger) break;
            in = bigger;
            cap *= 2;
        }
    }
    double *out = malloc((n + 1) * sizeof *out);
    if (!in || !out || n % 2) {
        fprintf(stderr, "expected pairs of doubles on stdin\n");
        return 2;
    }
    vkl_camera c = NULL;
    vkl_error e = vkl_camera_load(argv[1], &c);
    if (!e) {
        e = strcmp(argv[2], "distort") == 0 ? vkl_camera_distort_points(c, in, n / 2, out)
                                            : vkl_camera_undistort_points(c, in, n / 2, out);
    }
    if (e) {
        fprintf(stderr, "%s\n", vkl_error_message(e));
        vkl_error_free(&e);
        return 1;
    }
    fwrite(out, sizeof *out, n, stdout);
    vkl_camera_free(&c);
    free(in);
    free(out);
    return 0;
}
