// The plugin module libgam_test_sim_sensor.so: registers the test sensor when
// it is loaded (ground-aware-mapper --plugins, as rawlog-grabber -p), the way
// MRPT's own hwdrivers library registers its drivers.
#include <mrpt/core/initializer.h>

#include "CSimulatedSceneSensor.h"

MRPT_INITIALIZER(register_gam_test_sim_sensor) { gam_test::CSimulatedSceneSensor::doRegister(); }
