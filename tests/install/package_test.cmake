# Script behind the ctest package_find_package (tests/install/CMakeLists.txt): installs the build into
# WORK_DIR/prefix, builds the consumer project against it and runs it; fails with a message naming
# the step. Arguments (-D): BUILD_DIR SOURCE_DIR WORK_DIR GENERATOR BUILD_TYPE CXX_LAUNCHER PYTHON
# PYTHON_INSTALL_DIR (PYTHON empty: the module is not part of the build).
cmake_minimum_required(VERSION 3.18)

function(run_step name)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE result OUTPUT_VARIABLE output ERROR_VARIABLE errors)
  if(NOT result EQUAL 0)
    message(FATAL_ERROR "package test: ${name} failed (${result}):\n${output}\n${errors}")
  endif()
  set(step_output "${output}" PARENT_SCOPE)
endfunction()

set(prefix ${WORK_DIR}/prefix)
set(consumer ${WORK_DIR}/consumer)
file(REMOVE_RECURSE ${WORK_DIR})
file(MAKE_DIRECTORY ${WORK_DIR})

# 1. Install.
run_step("cmake --install" ${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${prefix})
file(GLOB_RECURSE config_files ${prefix}/*/QuadrixConfig.cmake)
list(LENGTH config_files config_count)
if(NOT config_count EQUAL 1)
  message(FATAL_ERROR "package test: expected one QuadrixConfig.cmake under ${prefix}, found: ${config_files}")
endif()
foreach(header estimation/registration.h estimation/registration_config.h geometry/io.h fitting/scene_model.h)
  if(NOT EXISTS ${prefix}/include/quadrix/${header})
    message(FATAL_ERROR "package test: header ${header} not installed under ${prefix}/include/quadrix")
  endif()
endforeach()
# The exported targets must not point back into the source or build tree.
get_filename_component(config_dir ${config_files} DIRECTORY)
file(GLOB target_files ${config_dir}/QuadrixTargets*.cmake)
foreach(target_file ${target_files})
  file(READ ${target_file} text)
  foreach(tree ${SOURCE_DIR} ${BUILD_DIR})
    string(FIND "${text}" "${tree}/" at)
    if(NOT at EQUAL -1)
      message(FATAL_ERROR "package test: ${target_file} refers to ${tree}")
    endif()
  endforeach()
endforeach()

# 2. A project outside the tree: the README's CMakeLists.txt and C++ example, copied as they are.
file(MAKE_DIRECTORY ${consumer})
configure_file(${SOURCE_DIR}/tests/install/consumer/CMakeLists.txt ${consumer}/CMakeLists.txt COPYONLY)
configure_file(${SOURCE_DIR}/docs/examples/register_two_clouds.cpp ${consumer}/register_two_clouds.cpp COPYONLY)
set(configure_arguments -S ${consumer} -B ${consumer}/build -G ${GENERATOR} -DCMAKE_PREFIX_PATH=${prefix})
if(BUILD_TYPE)
  list(APPEND configure_arguments -DCMAKE_BUILD_TYPE=${BUILD_TYPE})
endif()
if(CXX_LAUNCHER)
  list(APPEND configure_arguments -DCMAKE_CXX_COMPILER_LAUNCHER=${CXX_LAUNCHER})
endif()
run_step("configuring the consumer with find_package(Quadrix)" ${CMAKE_COMMAND} ${configure_arguments})
run_step("building the consumer" ${CMAKE_COMMAND} --build ${consumer}/build)

# 3. A simulated street pair from the installed executable, registered by the consumer: it exits 0
#    only when the status is ok, and prints the transform and "ok: ...".
run_step("installed quadrix synth" ${prefix}/bin/quadrix synth street --seed 3 --sensor hdl64 --out ${WORK_DIR}/street)
run_step("running the consumer" ${consumer}/build/register_two_clouds ${WORK_DIR}/street/scan_001.ply
         ${WORK_DIR}/street/scan_000.ply)
string(FIND "${step_output}" "ok:" at)
if(at EQUAL -1)
  message(FATAL_ERROR "package test: the consumer did not report ok:\n${step_output}")
endif()
message(STATUS "consumer output:\n${step_output}")

# 4. The installed Python module, imported from the prefix by Debian's python3.
if(PYTHON)
  run_step("importing the installed Python module" ${CMAKE_COMMAND} -E env PYTHONPATH=${prefix}/${PYTHON_INSTALL_DIR}
           ${PYTHON} -c "import quadrix\nprint(quadrix.__file__, quadrix.__version__)")
  string(FIND "${step_output}" "${prefix}/${PYTHON_INSTALL_DIR}/quadrix" at)
  if(NOT at EQUAL 0)
    message(FATAL_ERROR "package test: python imported quadrix from elsewhere: ${step_output}")
  endif()
endif()
