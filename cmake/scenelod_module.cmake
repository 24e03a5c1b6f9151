# scenelod_add_module(<target> <export-name> <dir> [SOURCES <file>...])
# One static library per module: its sources are every src/*.cpp of the folder (one algorithm per
# file, so adding a unit never touches a CMakeLists), public headers live in include/scenelod/<module>/.
# A folder split into several libraries (a per-frame core apart from its tooling) gives each one its
# SOURCES (from scenelod_glob_sources) and then calls scenelod_check_split(<dir> <targets>...).
function(scenelod_add_module target export_name dir)
  cmake_parse_arguments(PARSE_ARGV 3 _arg "" "" "SOURCES")
  if(_arg_SOURCES)
    set(_srcs ${_arg_SOURCES})
  else()
    file(GLOB _srcs CONFIGURE_DEPENDS ${dir}/src/*.cpp)
  endif()
  add_library(${target} STATIC ${_srcs})
  add_library(scenelod::${export_name} ALIAS ${target})
  set_target_properties(${target} PROPERTIES EXPORT_NAME ${export_name})
  target_compile_features(${target} PUBLIC cxx_std_17)
  target_include_directories(${target} PUBLIC
    $<BUILD_INTERFACE:${dir}/include>
    $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>
    PRIVATE ${dir}/src)
  target_link_libraries(${target} PRIVATE $<BUILD_INTERFACE:scenelod_warnings>)
  scenelod_install_target(${target})
  # the libraries of a split folder share its headers: install them once
  get_property(_installed GLOBAL PROPERTY SCENELOD_INSTALLED_HEADER_DIRS)
  if(SCENELOD_INSTALL AND NOT dir IN_LIST _installed)
    set_property(GLOBAL APPEND PROPERTY SCENELOD_INSTALLED_HEADER_DIRS ${dir})
    install(DIRECTORY ${dir}/include/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
  endif()
endfunction()

# scenelod_install_target(<target>): installs a library into the exported package.
function(scenelod_install_target target)
  if(SCENELOD_INSTALL)
    install(TARGETS ${target} EXPORT scenelodTargets
      ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
      LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
  endif()
endfunction()

# scenelod_glob_sources(<out-var> <dir> <pattern>...): the files of <dir>/src matching the patterns
# (e.g. selector*.cpp), so that a unit split into more files with the same prefix needs no edit here.
function(scenelod_glob_sources out dir)
  set(_files)
  foreach(_pattern ${ARGN})
    file(GLOB _found CONFIGURE_DEPENDS ${dir}/src/${_pattern})
    if(NOT _found)
      message(FATAL_ERROR "scenelod: no source in ${dir}/src matches ${_pattern}")
    endif()
    list(APPEND _files ${_found})
  endforeach()
  set(${out} ${_files} PARENT_SCOPE)
endfunction()

# scenelod_check_split(<dir> <target>...): fails the configure when a src/*.cpp of a split folder
# belongs to none of its libraries, or to two (a new file must be given to one of them).
function(scenelod_check_split dir)
  set(_claimed)
  foreach(_target ${ARGN})
    get_target_property(_srcs ${_target} SOURCES)
    list(APPEND _claimed ${_srcs})
  endforeach()
  file(GLOB _all CONFIGURE_DEPENDS ${dir}/src/*.cpp)
  foreach(_file ${_all})
    set(_count 0)
    foreach(_src ${_claimed})
      if(_src STREQUAL _file)
        math(EXPR _count "${_count} + 1")
      endif()
    endforeach()
    if(NOT _count EQUAL 1)
      message(FATAL_ERROR "scenelod: ${_file} is in ${_count} of the libraries ${ARGN}: give it to one")
    endif()
  endforeach()
endfunction()

# scenelod_add_umbrella(<target> <export-name> <library>...): an INTERFACE library linking the
# libraries a module was split into, under the module's old name, so that its users keep building.
function(scenelod_add_umbrella target export_name)
  add_library(${target} INTERFACE)
  add_library(scenelod::${export_name} ALIAS ${target})
  set_target_properties(${target} PROPERTIES EXPORT_NAME ${export_name})
  target_link_libraries(${target} INTERFACE ${ARGN})
  scenelod_install_target(${target})
endfunction()
