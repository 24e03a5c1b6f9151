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
