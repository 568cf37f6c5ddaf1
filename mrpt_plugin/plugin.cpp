/* ShadyLoc MRPT plugin: a shared module MRPT tools load with
 *   rawlog-edit -p ./libshadyloc_mrpt_plugin.so ...
 *   RawLogViewer -l ./libshadyloc_mrpt_plugin.so
 * Loading it registers every ShadyLoc class, so rawlogs and maps that hold
 * them can be read (libshadyloc's own initializer does the work; this module
 * makes sure the library is loaded and registered). */
#include <shadyloc/core/Registration.h>

#include <mrpt/core/initializer.h>

MRPT_INITIALIZER(shadyloc_plugin_init) { shadyloc::registerAllClasses(); }
