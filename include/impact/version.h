// The library's version, as CMakeLists.txt's project() states it; the installed
// package config matches the same major.minor (find_package(impact 0.1)).
#pragma once
/// Major version number.
#define IMPACT_VERSION_MAJOR 0
/// Minor version number.
#define IMPACT_VERSION_MINOR 1
/// Patch version number.
#define IMPACT_VERSION_PATCH 0
