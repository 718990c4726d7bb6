"""Desired responses: what a reconstruction is asked to reproduce, made, prepared and judged.

One module per concept (import the names from their module; the most used ones are also
:mod:`vrig`'s: ``vrig.pseudo_field``, ``vrig.desired_response``, ``vrig.f2d``,
``vrig.range_report``, ``vrig.check_target``):

* :mod:`vrig.desired.kinds`: a target name (``"pseudo-field"``, ``"field:<scenario>"``) made
  into a record (:func:`~vrig.desired.kinds.desired_response`, :func:`~vrig.desired.kinds.parse_target`);
* :mod:`vrig.desired.pseudo_field`: the rig's own response to a road-like drive;
* :mod:`vrig.desired.f2d`: field-to-desired processing of a measured record (channels, units,
  rate, band);
* :mod:`vrig.desired.range_report`: a desired response against the rig's transducer ranges;
* :mod:`vrig.desired.reachability`: which part of a target no drive reaches, the drive it needs,
  and the rule that scales it to the rig's limits;
* :mod:`vrig.desired.belgian_block`: a real road record (the Belgian block) as fuel-tank-7ch's
  desired response.

Where the records come from lives beside this package: :mod:`vrig.service` (a rig's specimen in
its vehicle, the field twin that makes service records) and :mod:`vrig.roads` (ISO 8608 road
profiles and events, the field twin's input).
"""
