#pragma once
// The whole public API of the autodiff engine.

#include "autodiff/functional.h"
#include "autodiff/grad.h"
#include "autodiff/gradcheck.h"
#include "autodiff/mlp_ops.h"
#include "autodiff/ops.h"
#include "autodiff/parallel.h"
#include "autodiff/tape.h"
#include "autodiff/var.h"
