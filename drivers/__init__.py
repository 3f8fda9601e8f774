"""touchbench: drivers, the sources of signal samples.

``source``       the :class:`~drivers.source.Source` interface: blocks with their times
``replay``       :class:`~drivers.replay.FileReplaySource`: any recording file, block by
                 block (audio, ``.npy``, CSV, ROS bags), as fast as possible or paced
``bags``         audio_common audio in ROS 1 and ROS 2 bags (``rosbags``, no ROS install)
``sound``        :class:`~drivers.sound.SoundDeviceSource`: sound-card capture (PortAudio)
``files``        read a recording (WAV/FLAC/..., CSV, ``.npy``) whole into a :class:`Recording`
``simulated``    synthetic contact-microphone sessions with known touches
``oscillating``  a simulated actively oscillated link with a 3-axis accelerometer

Every problem is a :class:`drivers.errors.DriverError`.  Import from the modules themselves
(``from drivers.recording import Recording``): the package imports nothing, so that catching
a driver's error does not load NumPy.
"""
