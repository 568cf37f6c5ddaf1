# cmake -P script: install into a scratch prefix, build the consumer project
# (examples/ and the one-pixel program) against it, then localise the first
# frames of the simulator's overcast run on a map of its noon run (the
# sim_sequences fixture, SIM_DIR) with the example, and check the outcome:
# enough frames localised, their poses within a few centimetres of the
# ground truth, the same poses from the filtered rawlog, a picture written,
# and no tools library in the example's links.
function(run what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(rc)
    message(FATAL_ERROR "${what} failed (${rc}):\n${out}${err}")
  endif()
  set(out "${out}" PARENT_SCOPE)
endfunction()

file(REMOVE_RECURSE ${WORK_DIR})
set(prefix ${WORK_DIR}/prefix)
run("install" ${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${prefix})
run("find_package(shadyloc) configure" ${CMAKE_COMMAND} -S ${SOURCE_DIR} -B ${WORK_DIR}/build
  -DCMAKE_PREFIX_PATH=${prefix} -DCMAKE_BUILD_TYPE=Release -DSHADYLOC_EXAMPLES_DIR=${EXAMPLES_DIR})
run("consumer build" ${CMAKE_COMMAND} --build ${WORK_DIR}/build)
run("one-pixel consumer" ${WORK_DIR}/build/consumer)
if(NOT out MATCHES "^[0-9]+")
  message(FATAL_ERROR "one-pixel consumer printed '${out}'")
endif()

# The example links the localisation library and not the tools library.
set(example ${WORK_DIR}/build/examples/localise_rawlog)
file(READ ${WORK_DIR}/build/examples/CMakeFiles/localise_rawlog.dir/link.txt link)
message(STATUS "the example's link line: ${link}")
run("ldd" ldd ${example})
if(NOT out MATCHES "libshadyloc_localisation" OR out MATCHES "libshadyloc_tools")
  message(FATAL_ERROR "the example should load libshadyloc_localisation and not libshadyloc_tools:\n${out}")
endif()

# ... and that library holds no simulator, dataset, evaluation or render code.
run("nm" nm -DC --defined-only ${prefix}/lib/libshadyloc_localisation.so)
if(out MATCHES "shadyloc::(sim|datasets|eval|render)::[A-Za-z_]+")
  message(FATAL_ERROR "libshadyloc_localisation defines ${CMAKE_MATCH_0}")
endif()

# The map of the noon run, by the installed program with the installed config.
set(env ${CMAKE_COMMAND} -E env LD_LIBRARY_PATH=${prefix}/lib)
set(cfg ${prefix}/share/shadyloc/config)
run("survey" ${env} ${prefix}/bin/shadyloc survey -q -i ${SIM_DIR}/noon.rawlog -o ${WORK_DIR}/noon.kfmap
  -c ${cfg}/vo_sim.ini)
run("example" ${example} ${WORK_DIR}/noon.kfmap ${SIM_DIR}/overcast.rawlog ${WORK_DIR}/overcast
  ${cfg}/vo_sim.ini ${cfg}/localise_sim.ini --frames ${FRAMES})
message(STATUS "the example printed:\n${out}")
string(REGEX MATCHALL "localised \\((mono|invariant|joint)\\)" fixes "${out}")
list(LENGTH fixes n)
if(n LESS ${MIN_FIXES})
  message(FATAL_ERROR "${n} of the first ${FRAMES} frames localised, expected at least ${MIN_FIXES}")
endif()

# The fixes against the ground truth (the map frame aligned to the world's).
run("traj-error" ${env} ${prefix}/bin/shadyloc traj-error --gt ${SIM_DIR}/overcast.tum --est ${WORK_DIR}/overcast.tum)
if(NOT out MATCHES "matched poses: +([0-9]+)")
  message(FATAL_ERROR "traj-error printed no matched poses:\n${out}")
endif()
if(NOT CMAKE_MATCH_1 EQUAL n)
  message(FATAL_ERROR "${CMAKE_MATCH_1} of the ${n} fixes have a ground-truth pose:\n${out}")
endif()
if(NOT out MATCHES "ATE RMSE: +([0-9.]+) m \\(mean [0-9.]+, max ([0-9.]+)\\)")
  message(FATAL_ERROR "traj-error printed no ATE:\n${out}")
endif()
if(CMAKE_MATCH_1 GREATER ${MAX_ATE_M} OR CMAKE_MATCH_2 GREATER ${MAX_ERR_M})
  message(FATAL_ERROR "fixes off the truth: ATE RMSE ${CMAKE_MATCH_1} m (<= ${MAX_ATE_M}), "
    "max ${CMAKE_MATCH_2} m (<= ${MAX_ERR_M})")
endif()
message(STATUS "${n} fixes, ATE RMSE ${CMAKE_MATCH_1} m, max ${CMAKE_MATCH_2} m")

# A filtered rawlog (the colour pairs with their derived grey channels
# beside them) localises to the same poses.
run("filter" ${env} ${prefix}/bin/shadyloc filter -q -i ${SIM_DIR}/overcast.rawlog -o ${WORK_DIR}/filtered.rawlog
  -c ${cfg}/filters_sim.ini)
run("example on the filtered rawlog" ${example} ${WORK_DIR}/noon.kfmap ${WORK_DIR}/filtered.rawlog
  ${WORK_DIR}/filtered ${cfg}/vo_sim.ini ${cfg}/localise_sim.ini --frames ${FRAMES})
file(READ ${WORK_DIR}/overcast.tum colour_tum)
file(READ ${WORK_DIR}/filtered.tum filtered_tum)
if(NOT colour_tum STREQUAL filtered_tum)
  message(FATAL_ERROR "the filtered rawlog localised to other poses than its colour original")
endif()

file(SIZE ${WORK_DIR}/overcast.png png_bytes)
if(png_bytes LESS 2000)
  message(FATAL_ERROR "the snapshot overcast.png has ${png_bytes} bytes")
endif()
