#pragma once
// The whole public API of the nn module.

#include "nn/activation.h"
#include "nn/atomic_file.h"
#include "nn/autoencoder.h"
#include "nn/constrained/constrained_model.h"
#include "nn/constrained/constraints.h"
#include "nn/constrained/mechanics.h"
#include "nn/dynamics.h"
#include "nn/hnn.h"
#include "nn/init.h"
#include "nn/linear.h"
#include "nn/lnn.h"
#include "nn/loss.h"
#include "nn/mlp.h"
#include "nn/module.h"
#include "nn/optim.h"
#include "nn/parameter_file.h"
