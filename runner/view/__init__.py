"""``scenario view``: a scenario live in a Panda3D window, the inputs played recorded as a variant, and
traces replayed side by side. Imports Panda3D's display modules (never ``panda3d.ode``), lazily.

Modules, engine-neutral first (nothing above ``window`` imports Panda3D at module level):

* :mod:`.keys`: Panda3D's button event names, the viewer's own keys, the events a scenario names.
* :mod:`.record`: ``--record``: the played inputs written into the scenario file as a new variant.
* :mod:`.script`: ``--script``: timed inputs, screenshots and closing without a person.
* :mod:`.camera`: the lab's camera, orbited with the mouse. :mod:`.hud`: the heads-up lines.
* :mod:`.tap`: the trace writer of a live run, also telling the window what it records.
* :mod:`.display`: opening ShowBase's window, or saying why there is none.
* :mod:`.window`: the window: reports.scene3d's scenes, camera, heads-up text, button events.
* :mod:`.audio`: the scenario's sounds through Panda3D's audio.
* :mod:`.live`: the session's step loop paced by the wall clock and fed by the window's inputs.
* :mod:`.replay`: traces replayed with a time slider. :mod:`.app`: the command's two paths.
"""
