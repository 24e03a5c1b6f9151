# cmake -P script run by the scenelod_install_consumer test: install, build the consumer, run it.
file(REMOVE_RECURSE "${WORK_DIR}")
file(MAKE_DIRECTORY "${WORK_DIR}")
set(prefix "${WORK_DIR}/prefix")

function(run_step name)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${name} failed (${rc}):\n${out}\n${err}")
  endif()
  set(step_output "${out}" PARENT_SCOPE)
endfunction()

run_step("install" ${CMAKE_COMMAND} --install "${BUILD_DIR}" --prefix "${prefix}")
if(NOT EXISTS "${prefix}/lib/cmake/scenelod/scenelodConfig.cmake" AND NOT EXISTS "${prefix}/lib64/cmake/scenelod/scenelodConfig.cmake"
   AND NOT EXISTS "${prefix}/lib/x86_64-linux-gnu/cmake/scenelod/scenelodConfig.cmake")
  file(GLOB_RECURSE found "${prefix}/*scenelodConfig.cmake")
  if(NOT found)
    message(FATAL_ERROR "the install tree has no scenelodConfig.cmake")
  endif()
endif()

# a sanitizer build installs static libraries that call the sanitizer runtimes: the consumer links them too
set(consumer_flags "")
if(SANITIZE)
  set(consumer_flags "-DCMAKE_EXE_LINKER_FLAGS=-fsanitize=address,undefined")
endif()
run_step("configure consumer" ${CMAKE_COMMAND} -S "${CONSUMER_SOURCE_DIR}" -B "${WORK_DIR}/build" -G "${GENERATOR}"
         -DCMAKE_BUILD_TYPE=${BUILD_TYPE} -DCMAKE_PREFIX_PATH=${prefix} ${consumer_flags})
run_step("build consumer" ${CMAKE_COMMAND} --build "${WORK_DIR}/build")

# a unit quad made of two triangles, plus one edge and one point
file(WRITE "${WORK_DIR}/quad.obj" "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 2 2\nf 1 2 3\nf 1 3 4\nl 4 5\np 5\n")
run_step("run consumer" "${WORK_DIR}/build/consumer" "${WORK_DIR}/quad.obj" "${WORK_DIR}/quad.glb")
message(STATUS "consumer said: ${step_output}")
set(expected "obj: nodes=1 meshes=1 vertices=5 triangles=2 edges=1 points=1\nglb: nodes=1 meshes=1 vertices=5 triangles=2 edges=1 points=1\n")
if(NOT step_output STREQUAL expected)
  message(FATAL_ERROR "unexpected consumer output:\n${step_output}\nexpected:\n${expected}")
endif()

# the per-frame core alone: it selects, and its link command names one library, its own archive
run_step("run selector consumer" "${WORK_DIR}/build/consumer_selector")
if(NOT step_output STREQUAL "levels: 0 1 2\n")
  message(FATAL_ERROR "unexpected selector consumer output:\n${step_output}")
endif()
set(link_txt "${WORK_DIR}/build/CMakeFiles/consumer_selector.dir/link.txt")
if(EXISTS "${link_txt}")
  file(READ "${link_txt}" link_command)
else()
  run_step("read the link command" ${CMAKE_COMMAND} --build "${WORK_DIR}/build" -- -t commands consumer_selector)
  string(REGEX MATCH "[^\n]*-o consumer_selector[^\n]*" link_command "${step_output}")
endif()
separate_arguments(link_args UNIX_COMMAND "${link_command}")
list(FILTER link_args INCLUDE REGEX "^-l|\\.(a|so)(\\.[0-9.]*)?$")
if(NOT link_args MATCHES "^[^;]*/libscenelod_selector\\.a$")
  message(FATAL_ERROR "the selector consumer links more than libscenelod_selector.a: ${link_args}\n${link_command}")
endif()
message(STATUS "selector consumer links: ${link_args}")

# the runtime scene graph alone: a scene and its pack round trip
run_step("run scene graph consumer" "${WORK_DIR}/build/consumer_scene_graph")
if(NOT step_output STREQUAL "scene: objects=2 radii 0.707 1.414\npack: objects=2 radii 0.707 1.414\n")
  message(FATAL_ERROR "unexpected scene graph consumer output:\n${step_output}")
endif()
