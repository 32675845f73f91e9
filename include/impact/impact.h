// Umbrella header: everything a user needs.
#pragma once

#include "impact/status.h"
#include "impact/types.h"
#include "impact/world.h"
#include "impact/broadphase.h"
#include "impact/firing.h"
#include "impact/integrators.h"
#include "impact/narrowphase.h"
#include "impact/raycast.h"
#include "impact/shape_queries.h"
#include "impact/shapes.h"
#include "impact/version.h"
