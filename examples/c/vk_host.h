/*
 * The host engine's own Vulkan, in plain C through the loader: what any engine already has
 * before it embeds vklens (an instance, a device with a compute queue, a command buffer,
 * images and buffers with their memory). Nothing here is vklens's.
 *
 * With VKLENS_VALIDATION=1 the Khronos validation layer is enabled and every message it
 * sends is printed and counted (host.validation_messages). VKLENS_DEVICE=cpu picks a CPU
 * device (lavapipe), VKLENS_DEVICE=gpu a discrete or integrated GPU; default: the first.
 */
#ifndef VK_HOST_H
#define VK_HOST_H

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <vulkan/vulkan.h>

#define VK_CHECK(call)                                                                 \
    do {                                                                               \
        VkResult vk_check_result_ = (call);                                            \
        if (vk_check_result_ != VK_SUCCESS) {                                          \
            fprintf(stderr, "%s:%d: %s failed: %d\n", __FILE__, __LINE__, #call,       \
                    (int)vk_check_result_);                                            \
            exit(1);                                                                   \
        }                                                                              \
    } while (0)

typedef struct {
    VkInstance instance;
    VkDebugUtilsMessengerEXT messenger;
    VkPhysicalDevice physical;
    VkDevice device;
    uint32_t family;
    VkQueue queue;
    VkCommandPool pool;
    VkCommandBuffer cmd;
    VkPhysicalDeviceMemoryProperties memory;
    int validation_messages;
} host;

typedef struct {
    VkImage image;
    VkImageView view;
    VkDeviceMemory memory;
    uint32_t width, height;
} host_image;

typedef struct {
    VkBuffer buffer;
    VkDeviceMemory memory;
    void *mapped;
    VkDeviceSize size;
} host_buffer;

static inline VKAPI_ATTR VkBool32 VKAPI_CALL host_on_message(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                                      VkDebugUtilsMessageTypeFlagsEXT type,
                                                      const VkDebugUtilsMessengerCallbackDataEXT *data,
                                                      void *user) {
    (void)type;
    if (severity >= VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT) {
        ((host *)user)->validation_messages += 1;
        fprintf(stderr, "validation: %s\n", data->pMessage);
    }
    return VK_FALSE;
}

static inline int host_wants_validation(void) {
    const char *v = getenv("VKLENS_VALIDATION");
    return v && (strcmp(v, "1") == 0 || strcmp(v, "true") == 0 || strcmp(v, "yes") == 0);
}

static inline VkPhysicalDevice host_pick_device(VkInstance instance) {
    uint32_t n = 0;
    VK_CHECK(vkEnumeratePhysicalDevices(instance, &n, NULL));
    if (n == 0) {
        fprintf(stderr, "no Vulkan device (install mesa-vulkan-drivers for lavapipe)\n");
        exit(1);
    }
    VkPhysicalDevice devices[16];
    if (n > 16) n = 16;
    VK_CHECK(vkEnumeratePhysicalDevices(instance, &n, devices));
    const char *want = getenv("VKLENS_DEVICE");
    for (uint32_t i = 0; want && i < n; i++) {
        VkPhysicalDeviceProperties p;
        vkGetPhysicalDeviceProperties(devices[i], &p);
        int cpu = p.deviceType == VK_PHYSICAL_DEVICE_TYPE_CPU;
        if ((strcmp(want, "cpu") == 0 && cpu) || (strcmp(want, "gpu") == 0 && !cpu)) return devices[i];
    }
    return devices[0];
}

/* Instance (with validation when asked), device with a compute queue and the one feature the
 * warp's R8 mask needs, a command pool and one primary command buffer. */
static inline void host_init(host *h) {
    memset(h, 0, sizeof *h);
    int validation = host_wants_validation();
    VkApplicationInfo app = {.sType = VK_STRUCTURE_TYPE_APPLICATION_INFO,
                             .pApplicationName = "vklens C host",
                             .apiVersion = VK_API_VERSION_1_1};
    const char *layers[] = {"VK_LAYER_KHRONOS_validation"};
    const char *extensions[] = {VK_EXT_DEBUG_UTILS_EXTENSION_NAME};
    VkDebugUtilsMessengerCreateInfoEXT messenger = {
        .sType = VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT,
        .messageSeverity = VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT |
                           VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT,
        .messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                       VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT,
        .pfnUserCallback = host_on_message,
        .pUserData = h};
    VkInstanceCreateInfo ici = {.sType = VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO,
                                .pNext = validation ? &messenger : NULL,
                                .pApplicationInfo = &app,
                                .enabledLayerCount = validation ? 1 : 0,
                                .ppEnabledLayerNames = layers,
                                .enabledExtensionCount = validation ? 1 : 0,
                                .ppEnabledExtensionNames = extensions};
    VK_CHECK(vkCreateInstance(&ici, NULL, &h->instance));
    if (validation) {
        PFN_vkCreateDebugUtilsMessengerEXT create = (PFN_vkCreateDebugUtilsMessengerEXT)vkGetInstanceProcAddr(
            h->instance, "vkCreateDebugUtilsMessengerEXT");
        if (create) VK_CHECK(create(h->instance, &messenger, NULL, &h->messenger));
    }
    h->physical = host_pick_device(h->instance);
    vkGetPhysicalDeviceMemoryProperties(h->physical, &h->memory);
    uint32_t nf = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(h->physical, &nf, NULL);
    VkQueueFamilyProperties families[16];
    if (nf > 16) nf = 16;
    vkGetPhysicalDeviceQueueFamilyProperties(h->physical, &nf, families);
    h->family = UINT32_MAX;
    for (uint32_t i = 0; i < nf && h->family == UINT32_MAX; i++)
        if (families[i].queueFlags & VK_QUEUE_COMPUTE_BIT) h->family = i;
    if (h->family == UINT32_MAX) {
        fprintf(stderr, "no compute queue\n");
        exit(1);
    }
    float priority = 1.0f;
    VkDeviceQueueCreateInfo qci = {.sType = VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO,
                                   .queueFamilyIndex = h->family,
                                   .queueCount = 1,
                                   .pQueuePriorities = &priority};
    VkPhysicalDeviceFeatures features = {.shaderStorageImageExtendedFormats = VK_TRUE};
    VkDeviceCreateInfo dci = {.sType = VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO,
                              .queueCreateInfoCount = 1,
                              .pQueueCreateInfos = &qci,
                              .pEnabledFeatures = &features};
    VK_CHECK(vkCreateDevice(h->physical, &dci, NULL, &h->device));
    vkGetDeviceQueue(h->device, h->family, 0, &h->queue);
    VkCommandPoolCreateInfo pci = {.sType = VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO,
                                   .flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT,
                                   .queueFamilyIndex = h->family};
    VK_CHECK(vkCreateCommandPool(h->device, &pci, NULL, &h->pool));
    VkCommandBufferAllocateInfo cai = {.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO,
                                       .commandPool = h->pool,
                                       .level = VK_COMMAND_BUFFER_LEVEL_PRIMARY,
                                       .commandBufferCount = 1};
    VK_CHECK(vkAllocateCommandBuffers(h->device, &cai, &h->cmd));
}

static inline uint32_t host_memory_type(const host *h, uint32_t bits, VkMemoryPropertyFlags want) {
    for (uint32_t i = 0; i < h->memory.memoryTypeCount; i++)
        if ((bits & (1u << i)) && (h->memory.memoryTypes[i].propertyFlags & want) == want) return i;
    fprintf(stderr, "no memory type with flags 0x%x\n", (unsigned)want);
    exit(1);
}

static inline host_image host_image_create(const host *h, uint32_t width, uint32_t height, VkFormat format,
                                    VkImageUsageFlags usage) {
    host_image img = {.width = width, .height = height};
    VkImageCreateInfo ici = {.sType = VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO,
                             .imageType = VK_IMAGE_TYPE_2D,
                             .format = format,
                             .extent = {width, height, 1},
                             .mipLevels = 1,
                             .arrayLayers = 1,
                             .samples = VK_SAMPLE_COUNT_1_BIT,
                             .tiling = VK_IMAGE_TILING_OPTIMAL,
                             .usage = usage,
                             .initialLayout = VK_IMAGE_LAYOUT_UNDEFINED};
    VK_CHECK(vkCreateImage(h->device, &ici, NULL, &img.image));
    VkMemoryRequirements req;
    vkGetImageMemoryRequirements(h->device, img.image, &req);
    VkMemoryAllocateInfo mai = {.sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO,
                                .allocationSize = req.size,
                                .memoryTypeIndex = host_memory_type(h, req.memoryTypeBits, 0)};
    VK_CHECK(vkAllocateMemory(h->device, &mai, NULL, &img.memory));
    VK_CHECK(vkBindImageMemory(h->device, img.image, img.memory, 0));
    VkImageViewCreateInfo vci = {.sType = VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO,
                                 .image = img.image,
                                 .viewType = VK_IMAGE_VIEW_TYPE_2D,
                                 .format = format,
                                 .subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1}};
    VK_CHECK(vkCreateImageView(h->device, &vci, NULL, &img.view));
    return img;
}

static inline void host_image_destroy(const host *h, host_image *img) {
    vkDestroyImageView(h->device, img->view, NULL);
    vkDestroyImage(h->device, img->image, NULL);
    vkFreeMemory(h->device, img->memory, NULL);
    memset(img, 0, sizeof *img);
}

/* A host-visible, coherent, persistently mapped buffer. */
static inline host_buffer host_buffer_create(const host *h, VkDeviceSize size, VkBufferUsageFlags usage) {
    host_buffer b = {.size = size};
    VkBufferCreateInfo bci = {.sType = VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO,
                              .size = size,
                              .usage = usage,
                              .sharingMode = VK_SHARING_MODE_EXCLUSIVE};
    VK_CHECK(vkCreateBuffer(h->device, &bci, NULL, &b.buffer));
    VkMemoryRequirements req;
    vkGetBufferMemoryRequirements(h->device, b.buffer, &req);
    VkMemoryAllocateInfo mai = {
        .sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO,
        .allocationSize = req.size,
        .memoryTypeIndex = host_memory_type(
            h, req.memoryTypeBits, VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT)};
    VK_CHECK(vkAllocateMemory(h->device, &mai, NULL, &b.memory));
    VK_CHECK(vkBindBufferMemory(h->device, b.buffer, b.memory, 0));
    VK_CHECK(vkMapMemory(h->device, b.memory, 0, VK_WHOLE_SIZE, 0, &b.mapped));
    return b;
}

static inline void host_buffer_destroy(const host *h, host_buffer *b) {
    vkDestroyBuffer(h->device, b->buffer, NULL);
    vkFreeMemory(h->device, b->memory, NULL);
    memset(b, 0, sizeof *b);
}

/* One image barrier: layout `from` -> `to`, (stage, access) before -> after. */
static inline void host_barrier(VkCommandBuffer cmd, VkImage image, VkImageLayout from, VkImageLayout to,
                         VkPipelineStageFlags src_stage, VkAccessFlags src_access,
                         VkPipelineStageFlags dst_stage, VkAccessFlags dst_access) {
    VkImageMemoryBarrier b = {.sType = VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER,
                              .srcAccessMask = src_access,
                              .dstAccessMask = dst_access,
                              .oldLayout = from,
                              .newLayout = to,
                              .srcQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED,
                              .dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED,
                              .image = image,
                              .subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1}};
    vkCmdPipelineBarrier(cmd, src_stage, dst_stage, 0, 0, NULL, 0, NULL, 1, &b);
}

/* Ends the command buffer, submits it, waits, and resets it for the next recording. */
static inline void host_submit_and_wait(const host *h) {
    VK_CHECK(vkEndCommandBuffer(h->cmd));
    VkFenceCreateInfo fci = {.sType = VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    VkFence fence;
    VK_CHECK(vkCreateFence(h->device, &fci, NULL, &fence));
    VkSubmitInfo si = {.sType = VK_STRUCTURE_TYPE_SUBMIT_INFO, .commandBufferCount = 1, .pCommandBuffers = &h->cmd};
    VK_CHECK(vkQueueSubmit(h->queue, 1, &si, fence));
    VK_CHECK(vkWaitForFences(h->device, 1, &fence, VK_TRUE, UINT64_MAX));
    vkDestroyFence(h->device, fence, NULL);
    VK_CHECK(vkResetCommandBuffer(h->cmd, 0));
}

static inline void host_begin(const host *h) {
    VkCommandBufferBeginInfo bi = {.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO,
                                   .flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT};
    VK_CHECK(vkBeginCommandBuffer(h->cmd, &bi));
}

static inline void host_destroy(host *h) {
    vkDestroyCommandPool(h->device, h->pool, NULL);
    vkDestroyDevice(h->device, NULL);
    if (h->messenger) {
        PFN_vkDestroyDebugUtilsMessengerEXT destroy = (PFN_vkDestroyDebugUtilsMessengerEXT)vkGetInstanceProcAddr(
            h->instance, "vkDestroyDebugUtilsMessengerEXT");
        if (destroy) destroy(h->instance, h->messenger, NULL);
    }
    vkDestroyInstance(h->instance, NULL);
}

#endif
