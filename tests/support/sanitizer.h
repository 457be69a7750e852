// kdmesh tests — KDMESH_UNDER_ASAN is 1 in a build with AddressSanitizer, under GCC (which
// defines __SANITIZE_ADDRESS__) and clang (which answers __has_feature; the CMake preset
// `sanitize` uses clang), else 0.
// SPDX-License-Identifier: AGPL-3.0-or-later
#pragma once

#if defined(__SANITIZE_ADDRESS__)
#define KDMESH_UNDER_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define KDMESH_UNDER_ASAN 1
#endif
#endif
#ifndef KDMESH_UNDER_ASAN
#define KDMESH_UNDER_ASAN 0
#endif
