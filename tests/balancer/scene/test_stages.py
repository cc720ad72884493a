"""The scene's stages (balancer.scene.stages) wired together: the drive's hand-over to the rotor."""

from balancer import run_scene

from support.scenes import DRIVE, ADB, scene


def test_drive_hands_speed_and_stiffness_to_the_rotor():
    config = scene(drive=DRIVE, rotor={"M": 2.0, "k": "drive:stiffness", "c": 20.0, "e": 1e-4},
                   adb={**ADB, "response": {"speed_rad_s": "drive:speed", "t_end_s": 0.2}},
                   outputs={"tables": ["rotor", "drive"]})
    run = run_scene(config)
    assert {s for s, v in run.stages.items() if v == "ran"} == {"drive", "rotor"}
    handover = run.results["drive"].handover
    # docs/drive.md worked example: 775 rpm = 81.158 rad/s, overhung 25 mm shaft: k = 403.2 kN/m
    assert abs(handover.speed_rad_s - 81.158) < 1e-3
    assert abs(handover.stiffness_n_per_m / 403.2e3 - 1) < 5e-4
    assert run.results["rotor"].params.k == handover.stiffness_n_per_m
