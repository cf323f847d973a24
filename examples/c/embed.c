/*
 * vklens inside a C host engine. The engine owns everything: instance, device, images,
 * buffers, command buffer and submission (vk_host.h). Into one command buffer it records
 *
 *   1. its own "render": a clear of the pinhole image to a dark blue, then a checkerboard
 *      copied into its middle from a staging buffer;
 *   2. vklens's map build (once) and warp: the pinhole image through the camera's lens;
 *   3. its own "present": copies of the pinhole and lens images to host buffers;
 *
 * submits it, waits, and writes OUT_DIR/source.ppm, OUT_DIR/lens.ppm and OUT_DIR/mask.pgm.
 * vklens creates no instance, device or queue, and submits nothing.
 *
 *   cc -std=c11 examples/c/embed.c $(pkg-config --cflags --libs vklens) -lvulkan -o embed
 *   ./embed examples/cameras/prism_tilt.json out/
 *
 * Exit status: 0 done, 1 an error (printed), 3 the validation layer spoke (VKLENS_VALIDATION=1).
 */
#include <stdio.h>
#include <stdlib.h>

#include <vklens.h>

#include "vk_host.h"

/* Prints a vklens error with what the host was doing, frees it, and exits. */
static void check(vkl_error e, const char *what) {
    if (e) {
        fprintf(stderr, "%s: %s\n", what, vkl_error_message(e));
        vkl_error_free(&e);
        exit(1);
    }
}

/* Writes `pixels` (RGBA8, width x height) as binary PPM (RGB) or, with gray, PGM (R only). */
static int write_pnm(const char *path, const unsigned char *pixels, uint32_t width, uint32_t height, int gray) {
    FILE *f = fopen(path, "wb");
    if (!f) {
        perror(path);
        return -1;
    }
    fprintf(f, "P%c\n%u %u\n255\n", gray ? '5' : '6', width, height);
    for (size_t i = 0; i < (size_t)width * height; i++) {
        fwrite(pixels + 4 * i, 1, gray ? 1 : 3, f);
    }
    return fclose(f);
}

int main(int argc, char **argv) {
    if (argc != 3) {
        fprintf(stderr, "usage: %s CAMERA_FILE OUT_DIR\n", argv[0]);
        return 2;
    }
    host h;
    host_init(&h);

    /* --- vklens, built from the engine's handles ------------------------------------------ */
    vkl_camera camera = NULL;
    check(vkl_camera_load(argv[1], &camera), argv[1]);
    vkl_vulkan vk = {.version = VKL_API_VERSION,
                     .instance = h.instance,
                     .physical_device = h.physical,
                     .device = h.device,
                     .queue = h.queue,
                     .queue_family_index = h.family,
                     .get_instance_proc_addr = vkGetInstanceProcAddr};
    vkl_gpu gpu = NULL;
    check(vkl_gpu_create(&vk, &gpu), "vkl_gpu_create");
    vkl_warp_options options = {.version = VKL_API_VERSION,
                                .direction = VKL_DISTORT,
                                .method = "lut",
                                .format = VK_FORMAT_R8G8B8A8_UNORM,
                                .fill = {0.0f, 0.0f, 0.0f, 0.0f}};
    vkl_warper warper = NULL;
    check(vkl_warper_create(gpu, camera, &options, &warper), "vkl_warper_create");
    uint32_t sw, sh, ow, oh;
    check(vkl_warper_source_size(warper, &sw, &sh), "vkl_warper_source_size");
    check(vkl_warper_output_size(warper, &ow, &oh), "vkl_warper_output_size");

    /* --- the engine's images and buffers ---------------------------------------------------- */
    VkImageUsageFlags usage =
        VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT;
    host_image pinhole = host_image_create(&h, sw, sh, VK_FORMAT_R8G8B8A8_UNORM, usage);
    host_image lens = host_image_create(&h, ow, oh, VK_FORMAT_R8G8B8A8_UNORM, usage);
    host_image mask = host_image_create(&h, ow, oh, VK_FORMAT_R8_UNORM, usage);
    /* The checkerboard covers the middle: 40 px squares, colours that change across it. */
    uint32_t cw = sw * 3 / 4, ch = sh * 3 / 4;
    host_buffer pattern = host_buffer_create(&h, (VkDeviceSize)cw * ch * 4, VK_BUFFER_USAGE_TRANSFER_SRC_BIT);
    unsigned char *p = pattern.mapped;
    for (uint32_t y = 0; y < ch; y++) {
        for (uint32_t x = 0; x < cw; x++) {
            unsigned char *q = p + 4 * ((size_t)y * cw + x);
            int on = ((x / 40) + (y / 40)) % 2;
            q[0] = on ? (unsigned char)(255 * x / cw) : 30;
            q[1] = on ? 230 : (unsigned char)(255 * y / ch);
            q[2] = on ? 40 : 200;
            q[3] = 255;
        }
    }
    host_buffer source_back = host_buffer_create(&h, (VkDeviceSize)sw * sh * 4, VK_BUFFER_USAGE_TRANSFER_DST_BIT);
    host_buffer lens_back = host_buffer_create(&h, (VkDeviceSize)ow * oh * 4, VK_BUFFER_USAGE_TRANSFER_DST_BIT);
    host_buffer mask_back = host_buffer_create(&h, (VkDeviceSize)ow * oh, VK_BUFFER_USAGE_TRANSFER_DST_BIT);

    /* --- one command buffer: the engine's passes around vklens's -------------------------- */
    host_begin(&h);
    VkCommandBuffer cmd = h.cmd;
    /* 1. the engine's "render" */
    host_barrier(cmd, pinhole.image, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
                 VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, 0, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT);
    VkClearColorValue blue = {.float32 = {0.05f, 0.1f, 0.3f, 1.0f}};
    VkImageSubresourceRange all = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
    vkCmdClearColorImage(cmd, pinhole.image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, &blue, 1, &all);
    host_barrier(cmd, pinhole.image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
                 VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT,
                 VK_ACCESS_TRANSFER_WRITE_BIT);
    VkBufferImageCopy middle = {.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1},
                                .imageOffset = {(int32_t)((sw - cw) / 2), (int32_t)((sh - ch) / 2), 0},
                                .imageExtent = {cw, ch, 1}};
    vkCmdCopyBufferToImage(cmd, pattern.buffer, pinhole.image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, &middle);
    /* vklens's contract: every image in GENERAL, the source's writes visible to the compute
     * shader's reads, the outputs ready for its writes. */
    host_barrier(cmd, pinhole.image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_IMAGE_LAYOUT_GENERAL,
                 VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                 VK_ACCESS_SHADER_READ_BIT);
    host_barrier(cmd, lens.image, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_GENERAL, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT,
                 0, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT);
    host_barrier(cmd, mask.image, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_GENERAL, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT,
                 0, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT);

    /* 2. vklens: the map build once, then the warp */
    vkl_image source_ref = {pinhole.image, pinhole.view, sw, sh};
    vkl_image lens_ref = {lens.image, lens.view, ow, oh};
    vkl_image mask_ref = {mask.image, mask.view, ow, oh};
    check(vkl_warper_record_prepare(warper, cmd), "vkl_warper_record_prepare");
    check(vkl_warper_record(warper, cmd, &source_ref, &lens_ref, &mask_ref), "vkl_warper_record");

    /* 3. the engine's "present": the warp's writes (compute) made visible to its copies */
    VkImage images[3] = {pinhole.image, lens.image, mask.image};
    VkAccessFlags before[3] = {VK_ACCESS_SHADER_READ_BIT, VK_ACCESS_SHADER_WRITE_BIT, VK_ACCESS_SHADER_WRITE_BIT};
    host_buffer *targets[3] = {&source_back, &lens_back, &mask_back};
    uint32_t widths[3] = {sw, ow, ow}, heights[3] = {sh, oh, oh};
    for (int i = 0; i < 3; i++) {
        host_barrier(cmd, images[i], VK_IMAGE_LAYOUT_GENERAL, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                     VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, before[i], VK_PIPELINE_STAGE_TRANSFER_BIT,
                     VK_ACCESS_TRANSFER_READ_BIT);
        VkBufferImageCopy whole = {.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1},
                                   .imageExtent = {widths[i], heights[i], 1}};
        vkCmdCopyImageToBuffer(cmd, images[i], VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, targets[i]->buffer, 1, &whole);
    }
    VkMemoryBarrier to_host = {.sType = VK_STRUCTURE_TYPE_MEMORY_BARRIER,
                               .srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT,
                               .dstAccessMask = VK_ACCESS_HOST_READ_BIT};
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &to_host, 0, NULL, 0,
                         NULL);
    host_submit_and_wait(&h);

    /* --- the results ------------------------------------------------------------------------ */
    char path[4096];
    int failed = 0;
    snprintf(path, sizeof path, "%s/source.ppm", argv[2]);
    failed |= write_pnm(path, source_back.mapped, sw, sh, 0) != 0;
    snprintf(path, sizeof path, "%s/lens.ppm", argv[2]);
    failed |= write_pnm(path, lens_back.mapped, ow, oh, 0) != 0;
    /* The mask is one byte a pixel: spread it to the 4-byte stride write_pnm reads. */
    unsigned char *mask_rgba = malloc((size_t)ow * oh * 4);
    if (!mask_rgba) return 1;
    for (size_t i = 0; i < (size_t)ow * oh; i++) mask_rgba[4 * i] = ((unsigned char *)mask_back.mapped)[i];
    snprintf(path, sizeof path, "%s/mask.pgm", argv[2]);
    failed |= write_pnm(path, mask_rgba, ow, oh, 1) != 0;
    free(mask_rgba);
    printf("warped %ux%u -> %ux%u into %s/lens.ppm\n", sw, sh, ow, oh, argv[2]);

    /* --- teardown: vklens's objects first, then the engine's ---------------------------- */
    vkl_warper_free(&warper);
    vkl_gpu_free(&gpu);
    vkl_camera_free(&camera);
    host_buffer_destroy(&h, &pattern);
    host_buffer_destroy(&h, &source_back);
    host_buffer_destroy(&h, &lens_back);
    host_buffer_destroy(&h, &mask_back);
    host_image_destroy(&h, &pinhole);
    host_image_destroy(&h, &lens);
    host_image_destroy(&h, &mask);
    int messages = h.validation_messages;
    host_destroy(&h);
    if (failed) return 1;
    if (messages) {
        fprintf(stderr, "%d validation message(s)\n", messages);
        return 3;
    }
    return 0;
}
