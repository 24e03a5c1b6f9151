# scenelod_add_module(<target> <export-name> <dir>)
# One static library per module: its sources are every src/*.cpp of the folder (one algorithm per
# file, so adding a unit never touches a CMakeLists), public headers live in include/scenelod/<module>/.
function(scenelod_add_module target export_name dir)
  file(GLOB _srcs CONFIGURE_DEPENDS ${dir}/src/*.cpp)
  add_library(${target} STATIC ${_srcs})
  add_library(scenelod::${export_name} ALIAS ${target})
  set_target_properties(${target} PROPERTIES EXPORT_NAME ${export_name})
  target_compile_features(${target} PUBLIC cxx_std_17)
  target_include_directories(${target} PUBLIC
    $<BUILD_INTERFACE:${dir}/include>
    $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>
    PRIVATE ${dir}/src)
  target_link_libraries(${target} PRIVATE $<BUILD_INTERFACE:scenelod_warnings>)
  if(SCENELOD_INSTALL)
    install(TARGETS ${target} EXPORT scenelodTargets
      ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
      LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
    install(DIRECTORY ${dir}/include/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
  endif()
endfunction()
