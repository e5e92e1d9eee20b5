"""The follower types (gears): the translating roller and the seeds' other valve gears (pivoted
roller lever, eccentric-driven rocking cam, eccentric rolling lever, trip gear with air or oil
dashpot), each a plug-in (explorer.gears.base.Gear) listed in explorer.gears.registry.

Each gear turns its geometry into what the rest of the pipeline consumes: a lift curve
(derivatives(theta) -> [L, L', L'', L'''], breakpoints()) with analytic derivatives, so the
kinematics, lash, forces and elastic effects work on it unchanged, and its own figures, variants
of effects and 'gear' report.
"""
