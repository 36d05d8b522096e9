#!/usr/bin/python3
"""Pressure-only feature survey for issue 13 (docs/detection.md, "Pressure transducers only").
Per 400-sample block (0.8 s) of a `leakmon sim` capture: db8 detail energies of levels 1-3 of
p1 and p2 (pywt.wavedec, symmetric), and from them
  L2    mean log level-2 energy of p1 and p2 (2 x the log of index_cusum's index)
  R13   log E2 - (log E1 + log E3)/2: level 2 against its neighbours (mean of p1, p2; R13p1: p1)
  R1p1, R3p1  level 2 against level 1, resp. 3, of p1 alone
  R12   log E2(p1) - log E2(p2): one chamber against the other
  C     zero-lag correlation of the level-2 details of p1 and p2 (Z: its Fisher z); C1, C3 the
        same at levels 1 and 3
  DS    log E2(p1 - p2) - log E2(p1 + p2): the antisymmetric against the common-mode band
Each feature's residual after a regression on the load (p1 - p2)/ps, its square and the log
activity of the reference, fitted on the healthy blocks.
  leak  CAPTURE...  leak at 300 s: shift of the mean residual over 302-362 s against the healthy
                    blocks 100-300 s, in healthy standard deviations (regressed/raw; r: lag-1)
  drift CAPTURE...  fit on 10-100 s; range of the 60 s moving mean of the residual over the run,
                    in healthy standard deviations (warm-up, supply changes)
Usage: pressure_features.py leak|drift CAPTURE.csv ..."""
import sys, numpy as np, pywt
B=400
def load(fn):
    with open(fn) as f:
        lines=[l for l in f if not l.startswith('#')]
    hdr=lines[0].strip().split(',')
    a=np.loadtxt(lines[1:],delimiter=',')
    return {h:a[:,i] for i,h in enumerate(hdr)}
def feats(d):
    n=len(d['t'])//B
    out=[]
    for k in range(n):
        s=slice(k*B,(k+1)*B)
        row={}
        dets={}
        for ch in ('p1','p2'):
            c=pywt.wavedec(d[ch][s],'db8',mode='symmetric',level=3)
            # c = [a3,d3,d2,d1]
            dets[ch]=c
            for j,lev in ((1,3),(2,2),(3,1)):
                row[f'E{j}{ch}']=np.mean(c[lev]**2)
        dd=pywt.wavedec(d['p1'][s]-d['p2'][s],'db8',mode='symmetric',level=3)
        sm=pywt.wavedec(d['p1'][s]+d['p2'][s],'db8',mode='symmetric',level=3)
        a,b=dets['p1'][2],dets['p2'][2]
        a=a-a.mean(); b=b-b.mean()
        f={}
        f['L2']=0.5*(np.log(row['E2p1'])+np.log(row['E2p2']))
        f['L2p1']=np.log(row['E2p1'])
        f['R13']=np.mean([np.log(row[f'E2{c}'])-0.5*(np.log(row[f'E1{c}'])+np.log(row[f'E3{c}'])) for c in ('p1','p2')])
        f['R13p1']=np.log(row['E2p1'])-0.5*(np.log(row['E1p1'])+np.log(row['E3p1']))
        f['R1p1']=np.log(row['E2p1'])-np.log(row['E1p1'])
        f['R3p1']=np.log(row['E2p1'])-np.log(row['E3p1'])
        f['R12']=np.log(row['E2p1'])-np.log(row['E2p2'])
        f['C']=np.sum(a*b)/np.sqrt(np.sum(a*a)*np.sum(b*b))
        for lev,nm in ((3,'C1'),(1,'C3')):
            a1,b1=dets['p1'][lev]-dets['p1'][lev].mean(),dets['p2'][lev]-dets['p2'][lev].mean()
            f[nm]=np.sum(a1*b1)/np.sqrt(np.sum(a1*a1)*np.sum(b1*b1))
        f['Z']=np.arctanh(np.clip(f['C'],-0.999,0.999))
        f['DS']=np.log(np.mean(dd[2]**2))-np.log(np.mean(sm[2]**2))
        f['LD']=np.log(np.mean(dd[2]**2))
        f['load']=np.mean(d['p1'][s]-d['p2'][s])/1.72e7
        f['sum']=np.mean(d['p1'][s]+d['p2'][s])/1.72e7
        f['act']=np.log(np.std(d['xref'][s])+1e-5)
        f['t']=d['t'][s][-1]
        if 'temp' in d: f['temp']=np.mean(d['temp'][s])
        out.append(f)
    return {k:np.array([o[k] for o in out]) for k in out[0]}
def resid(F,k,fit):
    X=np.column_stack([np.ones(len(F['load'])),F['load'],F['load']**2,F['act']])
    beta,*_=np.linalg.lstsq(X[fit],F[k][fit],rcond=None)
    return F[k]-X@beta
names=['C1','C3','L2','L2p1','R13','R13p1','R1p1','R3p1','R12','C','Z','DS','LD']
mode=sys.argv[1]
for fn in sys.argv[2:]:
    F=feats(load(fn)); t=F['t']
    if mode=='leak':
        fit=(t>100)&(t<300); post=(t>302)&(t<362)
        s=[]
        for k in names:
            r=resid(F,k,fit); sd=r[fit].std(); rho=np.corrcoef(r[fit][1:],r[fit][:-1])[0,1]
            raw=(F[k][post].mean()-F[k][fit].mean())/F[k][fit].std()
            s.append(f"{k}:{(r[post].mean()-r[fit].mean())/sd:+.2f}/{raw:+.2f}(r{rho:.1f})")
        rc=resid(F,'C',fit); rl=resid(F,'L2',fit); rr=resid(F,'R13',fit)
        for nm,comb in (('C-L2',rc/rc[fit].std()-rl/rl[fit].std()),('C-R13',rc/rc[fit].std()-rr/rr[fit].std())):
            s.append(f"{nm}:{(comb[post].mean()-comb[fit].mean())/comb[fit].std():+.2f}")
        s.append(f"Cmean:{F['C'][fit].mean():.2f}")
        print(fn.split('/')[-1],' '.join(s))
    else:
        fit=(t>10)&(t<100)
        s=[]
        for k in names:
            r=resid(F,k,fit); sd=r[fit].std()
            # 75-block (60 s) moving means of residual in sd units: max and min
            m=np.convolve(r,np.ones(75)/75,mode='valid')
            s.append(f"{k}:[{m.min()/sd:+.1f},{m.max()/sd:+.1f}]")
        print(fn.split('/')[-1],' '.join(s))
