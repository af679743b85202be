"""Learning the leader's downwash: labels, datasets, features, models, training and runtime.

The pipeline and its data only: the wake identified from flights is :mod:`aerodock.identify`,
the helpers of single experiments live beside them in :mod:`aerodock.experiments`, the
curriculum that flies the simulated world for data is :mod:`aerodock.collect`, and the ONNX
export and the deployment warnings are :mod:`aerodock.deploy`.

The modules split along one line: ``labels``, ``dataset``, ``datafiles``, ``splits``, ``features``,
``kinds`` (the registry of model kinds), ``modelfile``, ``training_vehicles``, ``runtime`` and
``evaluate`` are NumPy-only (everything the *deployed* path needs is among them), so a controller
can load a trained model without PyTorch; ``models`` and ``train`` import PyTorch. This
package's ``__init__`` imports nothing, on purpose: importing ``aerodock.learning.runtime``
must not pull in torch.

Typical use::

    from aerodock.learning.datafiles import load_data_paths
    from aerodock.learning.train import train_model
    from aerodock.learning.runtime import Predictor

    ds = load_data_paths([Path("flights/")])
    trained = train_model("so2", ds)
    trained.save("models/so2")
    predictor = Predictor.load("models/so2")
    f_ext_mps2 = predictor.predict_bodies(leader_state, follower_state)   # (n, 3), NED
"""
