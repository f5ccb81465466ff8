"""Solver engines, independent of any data kind: SCR (:mod:`symid.engine.scr`) and IPOPT (:mod:`symid.engine.ipopt`)."""
