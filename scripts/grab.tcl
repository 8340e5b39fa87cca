# Headless GTKWave: load the save file's signals, zoom to one frame, write a PNG, quit.
# Used by `make waves` to prove the waveform renders:
#   BISS_WAVES_PNG=out.png xvfb-run -a gtkwave -S scripts/grab.tcl dump.fst
set png [expr {[info exists ::env(BISS_WAVES_PNG)] ? $::env(BISS_WAVES_PNG) : "waves.png"}]
gtkwave::loadFile [file normalize [file join [file dirname [info script]] biss_master.gtkw]]
gtkwave::setZoomRangeTimes 40000000 62000000
gtkwave::/File/Grab_To_File $png
gtkwave::/File/Quit
