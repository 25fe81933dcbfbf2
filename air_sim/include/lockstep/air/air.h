// Umbrella header of the Lockstep air simulation core.
#pragma once

#include "lockstep/air/collision.h"
#include "lockstep/air/commands.h"
#include "lockstep/air/controller.h"
#include "lockstep/air/frames.h"
#include "lockstep/air/params.h"
#include "lockstep/air/types.h"
#include "lockstep/air/world.h"
