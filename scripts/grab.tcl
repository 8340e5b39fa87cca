# Headless GTKWave: show one frame of the save file's view, write a PNG, quit.
# scripts/waves.py runs it with the save file on the command line (so its [size] applies):
#   BISS_WAVES_PNG=out.png BISS_WAVES_FROM=t0 BISS_WAVES_TO=t1 [BISS_WAVES_MARKER=t] \
#     xvfb-run -a gtkwave -S scripts/grab.tcl dump.fst biss_master.gtkw
# The window is set here, after the layout exists: a zoom applied before the wave pane has its
# final width shows a different span.
set png [expr {[info exists ::env(BISS_WAVES_PNG)] ? $::env(BISS_WAVES_PNG) : "waves.png"}]
if {[info exists ::env(BISS_WAVES_FROM)] && [info exists ::env(BISS_WAVES_TO)]} {
    gtkwave::setZoomRangeTimes $::env(BISS_WAVES_FROM) $::env(BISS_WAVES_TO)
    gtkwave::setWindowStartTime $::env(BISS_WAVES_FROM)
    puts "grab: window [gtkwave::getWindowStartTime] .. [gtkwave::getWindowEndTime]"
}
# The primary marker: the signal pane shows the values at it.
if {[info exists ::env(BISS_WAVES_MARKER)]} {
    gtkwave::setMarker $::env(BISS_WAVES_MARKER)
}
gtkwave::/File/Grab_To_File $png
gtkwave::/File/Quit
