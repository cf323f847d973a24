/* Put in front of LLVM (LD_PRELOAD) by tests/frame_compiles.rs: says on stderr each module
 * LLVM is asked to start, which llvmpipe (lavapipe's compiler) does once per shader it
 * compiles, then hands the call on to LLVM. */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <stdio.h>

typedef void *(*create_fn)(const char *, void *);

void *LLVMModuleCreateWithNameInContext(const char *name, void *context) {
    static create_fn next;
    if (!next) {
        next = (create_fn)dlsym(RTLD_NEXT, "LLVMModuleCreateWithNameInContext");
    }
    fprintf(stderr, "vklens-compile: %s\n", name);
    return next(name, context);
}
