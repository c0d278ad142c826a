#!/usr/bin/python3
"""The radar's detections against the truth, per feature (issue 72 item 2's
radar score, NOTES.md session 32): for a run recorded with `--record
radar`, each detection of frames/radar/*.ply is labelled "drone" if within
3 m of the target's true position at its frame's time (the simulator's
truth: for choosing a node's score offline, never given to a node), and
the drone's and the other detections' SNR, distance of the radial velocity
outside the falling-rain window of its direction (radar_preprocessor.h),
range and elevation are summarised.

    build/uavsim run scenarios/mmaud_twin.json --duration 20 --record radar \
        --set /weather/rain_mm_h=10 --out RUN
    scripts/radar_detection_features.py RUN [RADAR_X RADAR_Y RADAR_Z]

The radar's position defaults to the twin's."""
import csv
import re
import sys

import numpy as np


def analyse(d, radar):
    T=np.array([(float(r['t_s']),float(r['x_m']),float(r['y_m']),float(r['z_m'])) for r in csv.DictReader(open(d+'/truth.csv'))])
    rows=[]
    frames = sorted(__import__("glob").glob(d + "/frames/radar/*.ply"))
    for k, path in enumerate(frames):
        b=open(path,'rb').read(); h=b.index(b'end_header\n')+11
        head=b[:h].decode(); n=int(re.search(r'element vertex (\d+)',head).group(1)); t=float(re.search(r't_capture_s ([\d.e+-]+)',head).group(1))
        pts=np.frombuffer(b[h:h+n*20],dtype='<f4').reshape(n,5)
        tr=T[np.argmin(abs(T[:,0]-t)),1:]
        for p in pts:
            dv=p[:3]-radar; r=np.linalg.norm(dv); uz=dv[2]/r
            a,bb=-9.65*uz,-2*uz; lo,hi=min(a,bb),max(a,bb)
            dop=max(lo-p[3],p[3]-hi,0)  # distance outside the rain window
            rows.append((k,np.linalg.norm(p[:3]-tr)<3,p[4],dop,r,uz,p[3],np.linalg.norm(tr-radar)))
    A=np.array(rows,dtype=float)
    drone=A[:,1]==1
    print(d, 'detections', len(A), 'drone', drone.sum(), 'frames with drone det', len(set(A[drone,0])))
    for name,col in [('snr',2),('dop_out',3),('range',4),('uz',5),('v',6)]:
        print(f"  {name:8s} drone p10/50/90 {np.percentile(A[drone,col],[10,50,90]).round(2)}  other {np.percentile(A[~drone,col],[10,50,90]).round(2)}")
    for thr in [6,8,10,12]:
        print(f"  snr>={thr}: drone {(A[drone,2]>=thr).sum()} other {(A[~drone,2]>=thr).sum()}")
    return A


if __name__ == "__main__":
    position = [float(v) for v in sys.argv[2:5]] if len(sys.argv) >= 5 else [-14.0, 0.0, 13.2]
    analyse(sys.argv[1], np.array(position))
