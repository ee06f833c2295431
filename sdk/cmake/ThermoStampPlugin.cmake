# thermostamp_add_plugin(NAME <name> KIND <element|material|thermal|contact>
#                        SOURCES <files...> [LIBRARIES <targets...>])
# Builds a plugin library named thermostamp_<kind>_<name>.so, the name the
# host looks for when a job asks for <name> of that kind. The same function
# builds the plugins of this source tree and, through
# find_package(ThermoStamp), plugins outside it.
function(thermostamp_add_plugin)
  cmake_parse_arguments(P "" "NAME;KIND" "SOURCES;LIBRARIES" ${ARGN})
  if(NOT P_NAME OR NOT P_KIND OR NOT P_SOURCES)
    message(FATAL_ERROR "thermostamp_add_plugin: NAME, KIND and SOURCES are required")
  endif()
  set(target thermostamp_${P_KIND}_${P_NAME})
  add_library(${target} MODULE ${P_SOURCES})
  target_link_libraries(${target} PRIVATE ThermoStamp::sdk ${P_LIBRARIES})
  set_target_properties(${target} PROPERTIES
    PREFIX ""
    OUTPUT_NAME ${target}
    CXX_VISIBILITY_PRESET hidden
    VISIBILITY_INLINES_HIDDEN ON)
  if(THERMOSTAMP_PLUGIN_OUTPUT_DIR)
    set_target_properties(${target} PROPERTIES LIBRARY_OUTPUT_DIRECTORY ${THERMOSTAMP_PLUGIN_OUTPUT_DIR})
  endif()
  set_property(GLOBAL APPEND PROPERTY THERMOSTAMP_PLUGIN_TARGETS ${target})
  if(THERMOSTAMP_INSTALL_PLUGINS)
    install(TARGETS ${target} LIBRARY DESTINATION lib/thermostamp/plugins)
  endif()
endfunction()
